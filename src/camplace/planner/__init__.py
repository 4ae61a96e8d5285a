"""camplace.planner (layer 12): ``camplace serve``, a local web app to adjust a placement by
hand (issue 20); between ``workflows`` (which it uses to prepare, evaluate and save) and ``cli``.
"""
