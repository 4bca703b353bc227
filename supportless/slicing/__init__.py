"""A real slicer's word: PrusaSlicer or Cura run on the written files, and their choice among answers.

* :mod:`.prusaslicer`: the PrusaSlicer bridge (slice, support filament, slice-check), which also
  hands a Cura slice to :mod:`.cura` (CuraEngine headless: normal or tree supports);
* :mod:`.choice`: which slicer and which support; :mod:`.jobs`: slicer runs in parallel, each with its logs;
* :mod:`.gcode`: reading a G-code summary (filament per feature, print time);
* :mod:`.ranking`: the slicer picks among the answers the search weighed.
"""
