"""The copyleft corner: every call into GPL/AGPL or non-commercial code inside libigl's wheel.

* :mod:`.cgal`: CGAL (GPL): exact self-intersection, self-union;
* :mod:`.tetgen`: TetGen (AGPL): volume meshes of a closed surface;
* :mod:`.triangle`: Shewchuk's Triangle (non-commercial use only): quality triangulations in 2D.

Nothing else in the package imports ``igl.copyleft`` or ``igl.triangle``, so
the licence questions and a possible replacement stay in these three files.
They import only :mod:`supportless.base.isolated` and :mod:`supportless.base.errors`
(Triangle not even those).
"""
