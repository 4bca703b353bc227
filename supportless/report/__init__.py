"""What a result is worth, in numbers and pictures.

* :mod:`.report`: measures of a pose (support, distortion, crossings) and the JSON report;
* :mod:`.render`: before/after pictures, convergence plots.
"""
