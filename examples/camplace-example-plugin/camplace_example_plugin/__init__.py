"""An example camplace plugin: the solver ``random-restarts`` (camplace_example_plugin.restarts)
and the visibility engine ``frustum`` (camplace_example_plugin.frustum), registered by the
entry points in its pyproject.toml. It uses only camplace's public API."""
