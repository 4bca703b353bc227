"""What a result is worth, in numbers and pictures.

* :mod:`.report`: measures of a pose (support, distortion, crossings) and the JSON report;
* :mod:`.render`: before/after pictures, convergence plots (:mod:`.projection`: their camera and framing);
* :mod:`.weakness`: the weak sections' colours and the weakest section's line on those pictures;
* :mod:`.outputs`: the one writer of a result's files (mesh, pose, pictures, report).
"""
