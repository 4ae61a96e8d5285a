"""The planner (issue 20): ``camplace serve``, a local web app to adjust a placement by hand.

Layer 12, between ``workflows`` (which it uses to prepare, evaluate and save) and ``cli``.
"""
