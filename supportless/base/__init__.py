"""What every stage stands on: errors, geometry and kinematics, and the process plumbing.

* :mod:`.errors`: the one-line errors a user reads (input, slicer, writing);
* :mod:`.geometry`: up directions, volumes, placing on the plate, the plate's frame;
* :mod:`.kinematics`: Euler angles -> bone transforms -> linear blend skinning;
* :mod:`.isolated`: native calls in a child process (a crash is an error, not a dead run);
* :mod:`.crash`: a command's supervisor (a crash in native code is one line naming the stage);
* :mod:`.lifetime`: a child ends with its parent, and gets the stop signals sent to the parent alone;
* :mod:`.interrupt`: Ctrl-C as a stop request read between steps; pause points for the tests;
* :mod:`.scratch`: temporary names a later run recognises and removes;
* :mod:`.terminal`: a stdout its reader may close; :mod:`.numba_cache`: numba's cache folder;
* :mod:`.threads`: a compiled kernel's loop split over threads.
"""
