"""camplace.outputs (layer 10): the files people and tools read - the contract files
(``write``), report.html and its figures, renders, exports (OpenCV, COLMAP) and the
hand-over plan set (PDF, SVG, DXF, glTF) and the cameras in the BIM model (``cameras_ifc``)."""
