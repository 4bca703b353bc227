"""Signed-distance primitives and the level-set mesher of the built-in figures.

A figure is the smooth union of *parts* (tapered capsules, axis-aligned
ellipsoids, rounded boxes), meshed as the zero level set of the union with
:meth:`manifold3d.Manifold.level_set` and cut flat at ``y = 0`` so it rests on
the build plate.  :class:`Body` collects the named joints, the bones and the
parts of one figure and meshes it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["Body", "Proportions", "box", "cap", "compact", "direction", "ell", "mesh_from_sdf", "unit"]

#: A part is skipped where a lower bound on its distance exceeds the running
#: union's value plus its blend radius by this much: the smooth minimum would
#: return the running value unchanged, so skipping it changes no bit.
_CULL_MARGIN = 1e-7

#: Shifts of the level set's grid, in edge lengths, tried in turn until the
#: mesh has no pinched vertex and no flat triangle (:func:`mesh_from_sdf`).
_GRID_SHIFTS = (0.0, 0.31, 0.57, 0.83)


# ---------------------------------------------------------------------------
# scalar signed-distance primitives (negative inside), compiled with numba
# ---------------------------------------------------------------------------

#: Kinds of parts, the first column of the parts table.
_CAP, _ELL, _BOX = 0.0, 1.0, 2.0
_KINDS = {"cap": _CAP, "ell": _ELL, "box": _BOX}
#: Columns of a row of the parts table: kind, blend radius, bounding-sphere
#: centre (3), squared slope and radius of the bound, then up to 8 parameters.
_COLUMNS = 15


@njit(cache=True, inline="always")
def _sd_capsule(px, py, pz, ax, ay, az, bx, by, bz, ra, rb):
    """Approximate signed distance to a tapered capsule (round cone).

    Parameters
    ----------
    px, py, pz : float
        Query point.
    ax, ay, az, bx, by, bz : float
        The segment's end points.
    ra, rb : float
        Radii at ``a`` and ``b``.

    Returns
    -------
    float
        Signed distance (negative inside).
    """
    bax, bay, baz = bx - ax, by - ay, bz - az
    pax, pay, paz = px - ax, py - ay, pz - az
    h = (pax * bax + pay * bay + paz * baz) / (bax * bax + bay * bay + baz * baz)
    h = 0.0 if h < 0.0 else (1.0 if h > 1.0 else h)
    dx, dy, dz = pax - bax * h, pay - bay * h, paz - baz * h
    return math.sqrt(dx * dx + dy * dy + dz * dz) - (ra + (rb - ra) * h)


@njit(cache=True, inline="always")
def _sd_ellipsoid(px, py, pz, cx, cy, cz, rx, ry, rz):
    """Approximate signed distance to an axis-aligned ellipsoid of centre ``c`` and semi-axes ``r``.

    Returns
    -------
    float
        Signed distance (negative inside); exact on the surface, a bound-like
        approximation elsewhere.
    """
    x, y, z = (px - cx) / rx, (py - cy) / ry, (pz - cz) / rz
    k0 = math.sqrt(x * x + y * y + z * z)
    x2, y2, z2 = x / rx, y / ry, z / rz
    k1 = math.sqrt(x2 * x2 + y2 * y2 + z2 * z2)
    if k1 == 0.0:
        return -min(rx, ry, rz)
    return k0 * (k0 - 1.0) / k1


@njit(cache=True, inline="always")
def _sd_box(px, py, pz, cx, cy, cz, hx, hy, hz, rr):
    """Exact signed distance to an axis-aligned box of centre ``c``, half extents ``h`` and edges rounded by ``rr``."""
    qx = abs(px - cx) - hx + rr
    qy = abs(py - cy) - hy + rr
    qz = abs(pz - cz) - hz + rr
    ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
    return math.sqrt(ox * ox + oy * oy + oz * oz) + min(max(qx, qy, qz), 0.0) - rr


@njit(cache=True, inline="always")
def _smin(a, b, k):
    """Polynomial smooth minimum of two distances: at most ``min(a, b)``, by up to ``k / 4`` where ``|a - b| < k``.

    ``k`` is the blend radius; 0 or less gives the plain minimum.
    """
    if k <= 0.0:
        return min(a, b)
    h = max(k - abs(a - b), 0.0) / k
    return min(a, b) - h * h * k * 0.25


@njit(cache=True)
def _union_value(x, y, z, table):
    """Smooth union of the parts in ``table`` (rows as :func:`_part_row`) at one point, positive inside.

    A part is skipped where the lower bound of its distance exceeds the
    running union plus its blend radius by :data:`_CULL_MARGIN`: the smooth
    minimum would return the running value unchanged, so no bit changes.
    """
    d = 1e9
    for i in range(table.shape[0]):
        row = table[i]
        k = row[1]
        t = d + k + _CULL_MARGIN
        if t > 0.0:
            dx, dy, dz = x - row[2], y - row[3], z - row[4]
            if row[5] * (dx * dx + dy * dy + dz * dz) >= (t + row[6]) * (t + row[6]):
                continue
        if row[0] == _CAP:
            b = _sd_capsule(x, y, z, row[7], row[8], row[9], row[10], row[11], row[12], row[13], row[14])
        elif row[0] == _ELL:
            b = _sd_ellipsoid(x, y, z, row[7], row[8], row[9], row[10], row[11], row[12])
        else:
            b = _sd_box(x, y, z, row[7], row[8], row[9], row[10], row[11], row[12], row[13])
        d = _smin(d, b, k)
    return -d


# ---------------------------------------------------------------------------
# parts
# ---------------------------------------------------------------------------

def _point(p):
    return tuple(float(x) for x in p)


def cap(a, b, ra, rb, k):
    """A tapered capsule part.

    Parameters
    ----------
    a, b : array_like, shape (3,)
        Segment end points.
    ra, rb : float
        Radii at ``a`` and ``b``.
    k : float
        Smooth-union blend radius with the parts before it.

    Returns
    -------
    tuple
        ``("cap", a, b, ra, rb, k)``.
    """
    return ("cap", _point(a), _point(b), float(ra), float(rb), float(k))


def ell(c, r, k):
    """An axis-aligned ellipsoid part.

    Parameters
    ----------
    c : array_like, shape (3,)
        Centre.
    r : array_like, shape (3,)
        Semi-axes.
    k : float
        Smooth-union blend radius with the parts before it.

    Returns
    -------
    tuple
        ``("ell", c, r, k)``.
    """
    return ("ell", _point(c), _point(r), float(k))


def box(c, h, rr, k):
    """An axis-aligned box part with rounded edges.

    Parameters
    ----------
    c : array_like, shape (3,)
        Centre.
    h : array_like, shape (3,)
        Half extents.
    rr : float
        Edge rounding radius.
    k : float
        Smooth-union blend radius with the parts before it.

    Returns
    -------
    tuple
        ``("box", c, h, rr, k)``.
    """
    return ("box", _point(c), _point(h), float(rr), float(k))


def _part_bound(part):
    """Bounding sphere of a part: ``(centre, s, R)`` with ``sd(p) >= s |p - centre| - R`` wherever that is positive."""
    kind = part[0]
    if kind == "cap":
        _, a, b, ra, rb, _ = part
        c = tuple(0.5 * (x + y) for x, y in zip(a, b))
        return c, 1.0, 0.5 * math.dist(a, b) + max(ra, rb)
    if kind == "ell":
        _, c, r, _ = part
        return c, min(r) / max(r), min(r)
    _, c, h, _, _ = part
    return c, 1.0, math.sqrt(sum(x * x for x in h))


def _part_row(part):
    """One row of the parts table: kind, blend radius, bound (centre, squared slope, radius), parameters."""
    c, slope, R = _part_bound(part)
    values = [x for v in part[1:-1] for x in (v if isinstance(v, tuple) else (v,))]
    row = [_KINDS[part[0]], part[-1], *c, slope * slope, R, *values]
    return row + [0.0] * (_COLUMNS - len(row))


def _union_sdf(parts):
    """The smooth union of ``parts`` as a scalar function ``f(x, y, z)``, positive inside (manifold3d's sign)."""
    table = np.array([_part_row(part) for part in parts], dtype=np.float64).reshape(-1, _COLUMNS)

    def sdf(x, y, z):
        return _union_value(x, y, z, table)

    return sdf


def mesh_from_sdf(parts, bounds, edge_length, cut_floor=True):
    """Mesh the smooth union of primitives with manifold3d's level set.

    Parameters
    ----------
    parts : list of tuple
        Parts made by :func:`cap`, :func:`ell` and :func:`box`, in the order
        they are added (each blends with the union of those before it).
    bounds : sequence of float
        ``[xmin, ymin, zmin, xmax, ymax, zmax]`` of the sampling box.
    edge_length : float
        Target edge length of the marching-tetrahedra grid.
    cut_floor : bool
        If true, keep only the part with ``y >= 0`` (flat feet).

    Returns
    -------
    V : numpy.ndarray, shape (n, 3), dtype float64
        Vertex positions.
    F : numpy.ndarray, shape (f, 3), dtype int64
        Outward-oriented triangles.
    """
    import manifold3d

    sdf = _union_sdf(parts)
    lo, hi = np.asarray(bounds[:3], dtype=np.float64), np.asarray(bounds[3:], dtype=np.float64)
    for shift in _GRID_SHIFTS:
        # where two sheets of the surface come closer than the grid spacing the
        # level set may snap both onto one place (a pinch) or fold a triangle
        # flat; the same surface sampled on a shifted grid usually has neither
        box = [*(lo - shift * edge_length), *(hi + shift * edge_length)]
        solid = manifold3d.Manifold.level_set(sdf, box, edge_length)
        if cut_floor:
            solid = solid.trim_by_plane((0.0, 1.0, 0.0), 0.0)
        V, F = _arrays(solid)
        if _is_clean(V, F, edge_length):
            return V, F
    raise RuntimeError("the level set has a pinched vertex or a flat triangle on every grid tried")


def _is_clean(V, F, edge_length):
    """No two vertices at one place and no triangle of zero area."""
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    flat = np.min(np.linalg.norm(np.cross(e1, e2), axis=1)) <= 1e-12 * edge_length ** 2
    return not flat and len(np.unique(V, axis=0)) == len(V)


def _arrays(solid):
    """Vertex and face arrays of a manifold3d solid, without unreferenced vertices."""
    mesh = solid.to_mesh()
    V = np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3].copy()
    F = np.asarray(mesh.tri_verts, dtype=np.int64).copy()
    return compact(V, F)


def compact(V, F):
    """Drop unreferenced vertices.

    Parameters
    ----------
    V : numpy.ndarray, shape (n, d), dtype float64
    F : numpy.ndarray, shape (f, 3), dtype int64

    Returns
    -------
    V2 : numpy.ndarray, shape (n2, d), dtype float64
    F2 : numpy.ndarray, shape (f, 3), dtype int64
    """
    used = np.unique(F)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[used] = np.arange(len(used), dtype=np.int64)
    return np.ascontiguousarray(V[used]), remap[F]


# ---------------------------------------------------------------------------
# figures under construction
# ---------------------------------------------------------------------------

def unit(v):
    """``v`` scaled to length 1.

    Parameters
    ----------
    v : array_like, shape (3,)

    Returns
    -------
    numpy.ndarray, shape (3,), dtype float64
    """
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def direction(azimuth, elevation):
    """Unit vector at ``azimuth`` degrees about ``+Y`` from ``+X`` (towards ``-Z``) and ``elevation`` degrees above the plate.

    Parameters
    ----------
    azimuth, elevation : float
        Degrees.

    Returns
    -------
    numpy.ndarray, shape (3,), dtype float64
    """
    a, e = math.radians(azimuth), math.radians(elevation)
    return np.array([math.cos(e) * math.cos(a), math.sin(e), -math.cos(e) * math.sin(a)])


class Proportions:
    """Random scale factors for a figure's proportions.

    Parameters
    ----------
    seed : int or None
        None gives the default figure: every factor is exactly 1.
    spread : float
        With a seed, factors are drawn uniformly from ``[1 - spread, 1 + spread]``.
    """

    def __init__(self, seed=None, spread=0.12):
        self._rng = None if seed is None else np.random.default_rng(seed)
        self.spread = float(spread)

    def __call__(self, x, spread=None):
        """``x`` times the next factor (``x`` itself without a seed).

        Parameters
        ----------
        x : float or numpy.ndarray
        spread : float, optional
            Overrides the default spread for this factor.

        Returns
        -------
        float or numpy.ndarray
        """
        if self._rng is None:
            return x
        s = self.spread if spread is None else spread
        return x * self._rng.uniform(1.0 - s, 1.0 + s)


class Body:
    """Named joints, bones and signed-distance parts of one figure.

    Joints are kept in the order they are added; :meth:`mesh` returns them as
    an array in that order, with the bones as index pairs.

    Parameters
    ----------
    seed : int, optional
        Seeds :attr:`vary`, the figure's :class:`Proportions`.
    """

    def __init__(self, seed=None):
        self.vary = Proportions(seed)
        self.joints: dict[str, np.ndarray] = {}
        self.bones: list[tuple[str, str]] = []
        self.parts: list[tuple] = []

    def __getitem__(self, name):
        return self.joints[name]

    def joint(self, name, p):
        """Add (or move) joint ``name`` at ``p``, shape (3,); returns its position."""
        self.joints[name] = np.asarray(p, dtype=np.float64)
        return self.joints[name]

    def bone(self, root, tip):
        """Add the bone ``[root, tip]`` between two named joints."""
        self.bones.append((root, tip))

    def add(self, *parts):
        """Append parts made by :func:`cap`, :func:`ell` or :func:`box`."""
        self.parts.extend(parts)

    def chain(self, names, radii, blends):
        """Bones along consecutive named joints, each wrapped in a tapered capsule.

        Parameters
        ----------
        names : sequence of str
            ``len(names) >= 2`` joints already added.
        radii : sequence of float
            A radius per joint, ``len(names)`` values.
        blends : float or sequence of float
            Blend radius of each capsule (``len(names) - 1`` values), or one for all.
        """
        if np.ndim(blends) == 0:
            blends = [blends] * (len(names) - 1)
        for i in range(len(names) - 1):
            a, b = names[i], names[i + 1]
            self.bone(a, b)
            self.add(cap(self[a], self[b], radii[i], radii[i + 1], blends[i]))

    def bounds(self, margin):
        """``[xmin, ymin, zmin, xmax, ymax, zmax]`` around every part, ``margin`` wider, and below ``y = 0``."""
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        for part in self.parts:
            kind = part[0]
            if kind == "cap":
                r = max(part[3], part[4])
                pts = np.array([part[1], part[2]])
                lo, hi = np.minimum(lo, pts.min(0) - r), np.maximum(hi, pts.max(0) + r)
            else:
                c, h = np.array(part[1]), np.array(part[2])
                lo, hi = np.minimum(lo, c - h), np.maximum(hi, c + h)
        lo, hi = lo - margin, hi + margin
        lo[1] = min(lo[1], -margin)
        return [float(x) for x in (*lo, *hi)]

    def mesh(self, edge_length):
        """Mesh the figure (cut flat at ``y = 0``) and return it with its skeleton.

        Parameters
        ----------
        edge_length : float
            Target edge length of the level set.

        Returns
        -------
        V : numpy.ndarray, shape (n, 3), dtype float64
        F : numpy.ndarray, shape (f, 3), dtype int64
        joints : numpy.ndarray, shape (j, 3), dtype float64
        bones : numpy.ndarray, shape (m, 2), dtype int64
        """
        V, F = mesh_from_sdf(self.parts, self.bounds(2.0 * edge_length), edge_length)
        names = list(self.joints)
        joints = np.array([self.joints[n] for n in names], dtype=np.float64)
        bones = np.array([[names.index(a), names.index(b)] for a, b in self.bones], dtype=np.int64)
        return V, F, joints, bones
