"""3MF files of the core specification: one mesh in millimetres, one build item.

A 3MF is a zip package (Open Packaging Conventions) holding a content-types
part, a relationship to the model part and the model XML. Only the core
namespace is written, so strict readers (the 3MF Consortium's ``lib3mf``)
accept it without warnings; coordinates are written exactly (shortest
round-trip decimal of each double).
"""

from __future__ import annotations

import zipfile

import numpy as np

__all__ = ["write_3mf"]

_3MF_CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
_3MF_CONTENT_TYPES = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
    '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
    '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
    '</Types>\n')
_3MF_RELS = (
    '<?xml version="1.0" encoding="UTF-8"?>\n'
    '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
    '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
    'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>'
    '</Relationships>\n')


def write_3mf(path, V: np.ndarray, F: np.ndarray) -> None:
    """A 3MF package of the core specification only: one mesh object in millimetres, one build item.

    The vertices are written as they are (a print file is already +Z up, on
    the plate, in mm); the build item has no transform, so a slicer places the
    object where its coordinates say.

    Parameters
    ----------
    path : str or os.PathLike
        Written as it is (callers make it atomic: :func:`supportless.files.meshes.write_mesh`).
    V : (n, 3) float64
    F : (f, 3) int64
    """
    vertices = "".join(f'<vertex x="{x!r}" y="{y!r}" z="{z!r}"/>' for x, y, z in V.tolist())
    triangles = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in F.tolist())
    model = (f'<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xml:lang="en-US" xmlns="{_3MF_CORE}">'
             '<metadata name="Application">supportless</metadata>'
             f'<resources><object id="1" type="model"><mesh><vertices>{vertices}</vertices>'
             f'<triangles>{triangles}</triangles></mesh></object></resources>'
             '<build><item objectid="1"/></build></model>\n')
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("[Content_Types].xml", _3MF_CONTENT_TYPES)
        z.writestr("_rels/.rels", _3MF_RELS)
        z.writestr("3D/3dmodel.model", model)
