"""A finite-element reference for the strength of a printed figure: linear elasticity on its tetrahedra.

The fast strength analysis (:mod:`supportless.energies.strength`: beam theory on layer and bone sections) is
checked against this module. It solves small-strain, isotropic linear elasticity on a tetrahedral mesh with
scikit-fem's quadratic (P2, default) or linear (P1) tetrahedra (:func:`elastic_solution`): some nodes held
still (:func:`plate_nodes`: those the plate holds), point loads and a body force (gravity) on the rest. The
Cauchy stress can then be read anywhere inside (:func:`stress_at`) or over a plane section
(:func:`section_stress`, :func:`section_normal_stress`). A rig's own volume mesh, posed and placed as it is
printed, is :func:`supportless.rig.posed_volume.posed_tet_mesh`.

Units everywhere: millimetres, newtons and MPa (N/mm²); the print frame has +Z up and the plate at the lowest z.

* **Stiffness and loads**: :mod:`supportless.energies.elasticity`. A point load is never applied at a point
  (the stress under a point force is infinite): it is spread as a body-force density over the tetrahedron
  containing the point (the nearest one for a point outside) and every tetrahedron sharing a vertex with it,
  or over those whose centroid is within ``load_radius``; the density is affine, with exactly the point
  force's resultant and moment (:func:`~supportless.energies.elasticity.point_load_density`).
* **Held nodes** are the only thing that removes the rigid motions (a ValueError when none is held, or all
  are on one line). For P2 an edge both of whose ends are held is held too.
* **Solve**: :mod:`supportless.energies.multigrid`, sparse LU when small, else conjugate gradients with a
  P2 → P1 → smoothed-aggregation V-cycle (``info`` says which, the iterations and the seconds).
* **Stress**: the P2 displacement's gradient is affine in each tetrahedron (P1: constant), so the stress is
  evaluated in the tetrahedron a point lies in; it jumps between tetrahedra, and a point on a shared face or
  edge takes one of them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from . import multigrid
from .elasticity import (body_force_density, check_fixed, held_nodes, hooke, lame_parameters, load_vector, locate,
                         prolongation, scalar_basis, stiffness_matrix)

__all__ = ["PLA_GRAVITY", "ElasticSolution", "SectionStress", "elastic_solution", "plate_nodes",
           "section_normal_stress", "section_stress", "stress_at", "stress_in"]

#: Gravity on PLA (1.24 g/cm³ × 9.81 m/s²) as a body force, N/mm³, +Z up.
PLA_GRAVITY = np.array([0.0, 0.0, -1.24e-3 * 9.81e-3])


@dataclass(eq=False)
class ElasticSolution:
    """A solved linear-elastic problem on a tetrahedral mesh.

    Attributes
    ----------
    nodes : (t, 3) float64
        Mesh vertices, mm.
    tets : (k, 4) int64
        Tetrahedra.
    order : int
        1 (linear tetrahedra) or 2 (quadratic).
    young_mpa : float
        Young's modulus, MPa.
    poisson : float
        Poisson's ratio.
    basis : skfem.CellBasis
        The scalar P1/P2 basis on the mesh; its degree of freedom (node) ``s`` carries ``displacement[s]``.
    displacement : (N, 3) float64
        Displacement of each node, mm: the ``t`` vertices first, then (P2) the edges' midpoints in the order
        of ``basis.mesh.edges``.
    fixed : (t,) bool
        The held vertices.
    info : dict
        ``solver``, ``unknowns``, ``iterations``, ``levels``, ``residual`` (see
        :func:`~supportless.energies.multigrid.solve_held`) and ``assembly_seconds``, ``solve_seconds``.
    """

    nodes: np.ndarray
    tets: np.ndarray
    order: int
    young_mpa: float
    poisson: float
    basis: object
    displacement: np.ndarray
    fixed: np.ndarray
    info: dict = field(default_factory=dict)

    @property
    def node_displacement(self) -> np.ndarray:
        """(t, 3) float64: the displacement of the mesh vertices, mm."""
        return self.displacement[: len(self.nodes)]


@dataclass(frozen=True)
class SectionStress:
    """The normal stress sampled over a plane section of a solved mesh.

    Attributes
    ----------
    normal : (3,) float64
        Unit normal of the plane.
    points : (s, 3) float64
        Sample points on the section, mm: the corners of the polygons where the plane cuts the tetrahedra, and
        points inside them.
    tets : (s,) int64
        The tetrahedron each point was evaluated in.
    normal_stress : (s,) float64
        ``n·σ·n`` at each point, MPa (positive: tension).
    """

    normal: np.ndarray
    points: np.ndarray
    tets: np.ndarray
    normal_stress: np.ndarray

    @property
    def max(self) -> float:
        """The largest normal stress over the section, MPa (negative when it is all in compression)."""
        return float(self.normal_stress.max())

    @property
    def where(self) -> np.ndarray:
        """(3,) float64: a point where :attr:`max` is reached, mm."""
        return self.points[int(np.argmax(self.normal_stress))]


def elastic_solution(nodes, tets, fixed, load_points=None, load_forces=None, body_force=None,
                     young_mpa: float = 3500.0, poisson: float = 0.35, order: int = 2,
                     load_radius: float | None = None) -> ElasticSolution:
    """Solve linear elasticity on a tetrahedral mesh held at some nodes.

    Parameters
    ----------
    nodes : (t, 3) float64
        Mesh vertices, mm.
    tets : (k, 4) int64
        Tetrahedra (either orientation). Vertices of no tetrahedron are held.
    fixed : (t,) bool
        Nodes held still (zero displacement), e.g. :func:`plate_nodes`; they must hold the mesh against
        every rigid motion.
    load_points : (L, 3) float64, optional
        Where point forces act, mm; each spread over the tetrahedra around it with its resultant and moment
        kept (see the module's docstring).
    load_forces : (L, 3) float64, optional
        The forces, N.
    body_force : (3,) float64, optional
        Force per volume, N/mm³, e.g. :data:`PLA_GRAVITY`.
    young_mpa : float
        Young's modulus, MPa (PLA about 3500).
    poisson : float
        Poisson's ratio.
    order : int
        2 for quadratic tetrahedra (the stress is affine in each), 1 for linear ones (constant).
    load_radius : float, optional
        Spread each point load over the tetrahedra whose centroid is within this many mm of it instead.

    Returns
    -------
    solution : ElasticSolution

    Raises
    ------
    ValueError
        No node fixed, or the fixed nodes all on one line; loads of mismatched shapes; a bad order or material.
    """
    t0 = time.perf_counter()
    nodes = np.asarray(nodes, np.float64)
    tets = np.asarray(tets, np.int64)
    fixed = check_fixed(nodes, fixed)
    lam, mu = lame_parameters(young_mpa, poisson)
    basis = scalar_basis(nodes, tets, order)
    K = stiffness_matrix(basis, lam, mu)
    f = load_vector(basis, body_force_density(basis, body_force, load_points, load_forces, load_radius))
    held = held_nodes(basis, fixed)
    coarse = None
    if order == 2 and 3 * int((~held).sum()) > multigrid.DIRECT_DOFS:
        coarse = (stiffness_matrix(scalar_basis(nodes, tets, 1), lam, mu), prolongation(basis))
    t1 = time.perf_counter()
    u, info = multigrid.solve_held(K, f, held, np.asarray(basis.doflocs).T, coarse)
    info.update(assembly_seconds=t1 - t0, solve_seconds=time.perf_counter() - t1)
    return ElasticSolution(nodes, tets, order, float(young_mpa), float(poisson), basis, u, fixed, info)


def stress_in(solution: ElasticSolution, cells: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The Cauchy stress at points, each evaluated in a given tetrahedron.

    Parameters
    ----------
    solution : ElasticSolution
    cells : (q,) int64
        The tetrahedron of each point (a point outside it extrapolates its affine stress).
    points : (q, 3) float64
        mm.

    Returns
    -------
    stress : (q, 3, 3) float64
        MPa, symmetric.
    """
    basis = solution.basis
    cells = np.asarray(cells, np.int64)
    points = np.atleast_2d(np.asarray(points, np.float64))
    if len(cells) == 0:
        return np.zeros((0, 3, 3))
    X = basis.mapping.invF(points.T[:, :, None], tind=cells)  # (3, q, 1) reference coordinates
    grad = np.zeros((len(cells), 3, 3))  # grad[q, c, d] = d u_c / d x_d
    for k in range(basis.Nbfun):
        dphi = basis.elem.gbasis(basis.mapping, X, k, tind=cells)[0].grad[:, :, 0]  # (3, q)
        u = solution.displacement[basis.element_dofs[k, cells]]  # (q, 3)
        grad += u[:, :, None] * dphi.T[:, None, :]
    strain = 0.5 * (grad + np.swapaxes(grad, 1, 2))
    return hooke(strain, *lame_parameters(solution.young_mpa, solution.poisson))


def stress_at(solution: ElasticSolution, points) -> np.ndarray:
    """The Cauchy stress at arbitrary points of the mesh.

    Each point is evaluated in the tetrahedron containing it; a point outside every tetrahedron at the nearest
    point of the mesh's boundary, in that boundary face's tetrahedron
    (:func:`~supportless.energies.elasticity.locate`).

    Parameters
    ----------
    solution : ElasticSolution
    points : (q, 3) float64
        mm.

    Returns
    -------
    stress : (q, 3, 3) float64
        MPa.
    """
    cells, where = locate(solution.nodes, solution.tets, np.atleast_2d(np.asarray(points, np.float64)))
    return stress_in(solution, cells, where)


def section_polygons(nodes: np.ndarray, tets: np.ndarray, origin: np.ndarray, normal: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where a plane cuts the tetrahedra: one convex polygon (3 or 4 corners) per tetrahedron cut.

    A vertex on the plane counts as below it (``(x - origin)·n <= 0``), so a face lying in the plane is cut
    once, from the tetrahedron above it.

    Parameters
    ----------
    nodes : (t, 3) float64
    tets : (k, 4) int64
    origin : (3,) float64
    normal : (3,) float64
        Unit.

    Returns
    -------
    cut : (c,) int64
        The tetrahedra cut.
    corners : (c, 4, 3) float64
        The polygons' corners (on the tetrahedra's edges); a triangle's fourth row repeats its first.
    count : (c,) int64
        3 or 4.
    """
    s = (nodes - origin) @ normal
    above = s[tets] > 0
    cut = np.flatnonzero(above.any(axis=1) & ~above.all(axis=1))
    pairs = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])
    a, b = tets[cut][:, pairs[:, 0]], tets[cut][:, pairs[:, 1]]  # (c, 6)
    crosses = above[cut][:, pairs[:, 0]] != above[cut][:, pairs[:, 1]]
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.where(crosses, s[a] / (s[a] - s[b]), 0.0)
    points = nodes[a] + w[:, :, None] * (nodes[b] - nodes[a])  # (c, 6, 3)
    order = np.argsort(~crosses, axis=1, kind="stable")[:, :4]  # the crossing edges first
    count = crosses.sum(axis=1)
    corners = np.take_along_axis(points, order[:, :, None], axis=1)
    corners[count == 3, 3] = corners[count == 3, 0]
    return cut, corners, count


def _section_pieces(tets: np.ndarray, cut: np.ndarray) -> np.ndarray:
    """(c,) int64: the connected piece of the section each cut tetrahedron is in (cut neighbours across faces)."""
    local = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
    faces = np.sort(tets[cut][:, local], axis=2).reshape(-1, 3)
    owner = np.repeat(np.arange(len(cut)), 4)
    _, inverse = np.unique(faces, axis=0, return_inverse=True)
    order = np.argsort(inverse.ravel(), kind="stable")
    inv = inverse.ravel()[order]
    same = np.flatnonzero(inv[1:] == inv[:-1])
    a, b = owner[order][same], owner[order][same + 1]
    graph = sp.coo_matrix((np.ones(len(a)), (a, b)), shape=(len(cut), len(cut)))
    return connected_components(graph, directed=False)[1]


def section_stress(solution: ElasticSolution, origin, normal, near=None, radius: float | None = None,
                   samples: int = 2) -> SectionStress:
    """The normal stress ``n·σ·n`` sampled over a plane section of the mesh.

    The plane cuts each tetrahedron it crosses in a convex polygon; each polygon is sampled at its corners (on
    the tetrahedron's edges, so on the mesh's boundary too), its centroid and the points a fraction ``j /
    samples`` of the way from the centroid to each corner, evaluated in that tetrahedron. The P2 stress is
    affine in a tetrahedron (P1: constant), so the largest value over a polygon is at a corner: the corners
    alone give the section's exact maximum; the inner points show the field.

    Parameters
    ----------
    solution : ElasticSolution
    origin : (3,) float64
        A point of the plane, mm.
    normal : (3,) float64
        Its normal (any length).
    near : (3,) float64, optional
        Keep only one part of the section: the points within ``radius`` of ``near``, or without ``radius`` the
        connected piece of the section (cut tetrahedra joined by faces) with the polygon nearest ``near``:
        one limb's section where the plane cuts several.
    radius : float, optional
        mm; needs ``near``.
    samples : int
        Inner points per centroid-to-corner segment (at least 1: the centroid).

    Returns
    -------
    section : SectionStress

    Raises
    ------
    ValueError
        The plane misses the mesh (or the part near ``near``); ``radius`` without ``near``.
    """
    n = np.asarray(normal, np.float64).reshape(3)
    n = n / np.linalg.norm(n)
    origin = np.asarray(origin, np.float64).reshape(3)
    if radius is not None and near is None:
        raise ValueError("radius needs near: the point the kept part of the section is around")
    cut, corners, count = section_polygons(solution.nodes, solution.tets, origin, n)
    if len(cut) == 0:
        raise ValueError(f"the plane through {origin.tolist()} with normal {n.tolist()} misses the mesh")
    centroid = (corners.sum(axis=1) - np.where(count[:, None] == 3, corners[:, 3], 0.0)) / count[:, None]
    if near is not None and radius is None:
        pieces = _section_pieces(solution.tets, cut)
        keep = pieces == pieces[np.argmin(np.linalg.norm(centroid - np.asarray(near, np.float64), axis=1))]
        cut, corners, count, centroid = cut[keep], corners[keep], count[keep], centroid[keep]
    fractions = np.arange(max(int(samples), 1)) / max(int(samples), 1)
    inner = centroid[:, None, None] + fractions[None, :, None, None] * (corners - centroid[:, None])[:, None]
    points = np.concatenate([corners, inner.reshape(len(cut), -1, 3)], axis=1)
    tets = np.broadcast_to(cut[:, None], points.shape[:2])
    points, tets = points.reshape(-1, 3), tets.ravel()
    if radius is not None:
        within = np.linalg.norm(points - np.asarray(near, np.float64), axis=1) <= radius
        points, tets = points[within], tets[within]
        if not len(points):
            raise ValueError(f"the plane's section has no point within {radius} mm of {list(near)}")
    stress = stress_in(solution, tets, points)
    return SectionStress(n, points, tets, np.einsum("i,qij,j->q", n, stress, n))


def section_normal_stress(solution: ElasticSolution, origin, normal, near=None, radius: float | None = None,
                          samples: int = 2) -> float:
    """The largest normal stress ``n·σ·n`` over a plane section, MPa (tension positive).

    :func:`section_stress`'s maximum (its ``where`` says where it is reached); same parameters.

    Returns
    -------
    stress : float
        MPa; negative when the whole section is in compression.
    """
    return section_stress(solution, origin, normal, near, radius, samples).max


def plate_nodes(nodes, tolerance_mm: float = 0.2) -> np.ndarray:
    """The nodes the build plate holds: those within the first layer of the lowest point.

    Parameters
    ----------
    nodes : (t, 3) float64
        In the print frame (+Z up), mm.
    tolerance_mm : float
        The first layer's height.

    Returns
    -------
    held : (t,) bool
    """
    z = np.asarray(nodes, np.float64)[:, 2]
    return z <= z.min() + tolerance_mm
