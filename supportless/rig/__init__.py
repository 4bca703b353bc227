"""The rig: surface, skeleton, tetrahedra and skinning weights, prepared once and cached.

* :mod:`.rig`: :class:`~supportless.rig.rig.Rig` (posing, self-intersection) and :func:`prepare_rig`;
* :mod:`.load`: :func:`load_rig` from files: skeleton read or built from the shape, printing direction, cache;
* :mod:`.tetmesh`: volume meshes (TetGen, else fTetWild; Triangle in 2D);
* :mod:`.weights`: bounded biharmonic weights; :mod:`.cache`: the on-disk cache shared by runs;
* :mod:`.balance`: centre of mass, support polygon and stability of a posed body.
"""
