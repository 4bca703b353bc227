"""The copyleft corner: every call into GPL/AGPL code inside libigl's wheel.

* :mod:`.cgal`: CGAL (GPL): exact self-intersection, self-union;
* :mod:`.tetgen`: TetGen (AGPL): volume meshes of a closed surface.

Nothing else in the package imports ``igl.copyleft``, so the licence
questions and a possible replacement stay in these two files. Both import
only :mod:`supportless.base.isolated` and :mod:`supportless.base.errors`.
"""
