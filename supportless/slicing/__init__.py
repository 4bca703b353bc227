"""A real slicer's word: PrusaSlicer run on the written files, and its choice among answers.

* :mod:`.prusaslicer`: the PrusaSlicer bridge (slice, support filament, slice-check);
* :mod:`.gcode`: reading a G-code summary (filament per feature, print time);
* :mod:`.ranking`: PrusaSlicer picks among the answers the search weighed.
"""
