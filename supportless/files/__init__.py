"""What a model's files say: meshes, skeletons, glTF, pose files, printers and the print frame.

* :mod:`.meshes`: meshes, TGF skeletons and DMAT weights in and out;
* :mod:`.threemf`: 3MF of the core specification; :mod:`.repair`: degenerate triangles removed;
* :mod:`.skeleton`: a skeleton is a tree of bones with length; :mod:`.joints`: joint order,
  skeletons from a glTF skin's joints, joints pulled inside the surface;
* :mod:`.gltf_skin`: a glTF skin in its rest pose, every joint posed by its whole ancestry
  (:mod:`.gltf_decode`: Draco and meshopt); :mod:`.gltf`: the character from it, posed assets out;
* :mod:`.printbody`: the one closed body to print from a character's overlapping parts
  (:mod:`.crossings`: a surface that crosses itself made one solid; :mod:`.surfaceops`: the small
  operations on a surface carrying values they are made of);
* :mod:`.posefile`: pose files (their bone tree and print frame);
* :mod:`.printframe`: the print frame (+Z up, millimetres, on the plate, the reference height);
* :mod:`.printer`: printer profiles (the overhang threshold, filament units);
* :mod:`.paths`: output locations checked before any work; atomic writes.
"""
