"""camplace.cameras (layer 4): models (lens models and the compiled projection), calibration
(OpenCV / ROS / JSON calibration files), candidates (candidate poses from the mounts)."""
