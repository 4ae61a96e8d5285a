"""An example camplace plugin: the solver ``random-restarts`` (camplace_example_plugin.restarts),
the visibility engine ``frustum`` (camplace_example_plugin.frustum), the plan format
``geojson`` (camplace_example_plugin.geojson) and the output file camera_coverage.csv
(camplace_example_plugin.coverage_csv), registered by the entry points in its
pyproject.toml. It uses only camplace's public API."""
