"""Linear elasticity on tetrahedra: the stiffness matrix, the loads and the held nodes.

scikit-fem provides the mesh, the scalar P1/P2 element, its quadrature and its degrees of freedom (vertices
first, then one per edge for P2); the 3D elasticity matrix is assembled here from the scalar basis' gradients,
in 3 × 3 blocks, one batched product per chunk of elements (scikit-fem's generic vector assembly takes about
45 s for 23 000 P2 tetrahedra on this machine, this about one). A node is a scalar degree of freedom ``s``;
its displacement's degrees of freedom are ``3 s + c``, ``c`` the component.

Point loads are never applied at a point (the stress under a point force is infinite). Each is spread as a
body-force density over a patch of tetrahedra around it (:func:`load_patch`): an affine density whose
resultant and moment are the point force's (:func:`point_load_density`).

Units: millimetres, newtons, MPa (N/mm²). Used by :mod:`supportless.energies.strength_fem`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit

__all__ = ["CHUNK", "barycentric", "block_pattern", "body_force_density", "boundary_faces", "check_fixed",
           "held_nodes", "hooke", "lame_parameters", "load_patch", "load_vector", "locate", "point_load_density",
           "prolongation", "restrict_blocks", "scalar_basis", "stiffness_matrix"]

#: Elements assembled per chunk (bounds the memory of the element matrices: 4000 P2 tets are 29 MB).
CHUNK = 4000


# ----------------------------------------------------------------------------------------------- material
def lame_parameters(young_mpa: float, poisson: float) -> tuple[float, float]:
    """Lamé's parameters of an isotropic material.

    Parameters
    ----------
    young_mpa : float
        Young's modulus, MPa.
    poisson : float
        Poisson's ratio, in (-1, 0.5).

    Returns
    -------
    lam, mu : float
        MPa.
    """
    if not (-1.0 < poisson < 0.5) or not young_mpa > 0:
        raise ValueError(f"need young_mpa > 0 and -1 < poisson < 0.5, got {young_mpa!r}, {poisson!r}")
    return (young_mpa * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)), young_mpa / (2.0 * (1.0 + poisson)))


def hooke(strain: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Cauchy stress of small strains, ``λ tr(ε) I + 2 μ ε``.

    Parameters
    ----------
    strain : (..., 3, 3) float64
    lam, mu : float
        Lamé's parameters, MPa.

    Returns
    -------
    stress : (..., 3, 3) float64
        MPa.
    """
    trace = np.trace(strain, axis1=-2, axis2=-1)
    return 2.0 * mu * strain + lam * trace[..., None, None] * np.eye(3)


# --------------------------------------------------------------------------------------------------- mesh
def scalar_basis(nodes: np.ndarray, tets: np.ndarray, order: int):
    """scikit-fem's scalar P1/P2 basis on a tetrahedral mesh, with the quadrature exact for stiffness and loads.

    Parameters
    ----------
    nodes : (t, 3) float64
    tets : (k, 4) int64
    order : int
        1 or 2.

    Returns
    -------
    basis : skfem.CellBasis
        Degree-2 quadrature (4 points): the products of P2 gradients, and of a P2 function with an affine
        density, are integrated exactly.
    """
    import skfem

    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    mesh = skfem.MeshTet(np.ascontiguousarray(np.asarray(nodes, np.float64).T),
                         np.ascontiguousarray(np.asarray(tets, np.int64).T))
    element = skfem.ElementTetP2() if order == 2 else skfem.ElementTetP1()
    return skfem.Basis(mesh, element, intorder=2)


def _vector_dofs(element_dofs: np.ndarray) -> np.ndarray:
    """(e, b*3) int64: the displacement degrees of freedom ``3 s + c`` of elements' scalar dofs ``(b, e)``."""
    return (3 * element_dofs.T.astype(np.int64)[:, :, None] + np.arange(3)).reshape(element_dofs.shape[1], -1)


def _element_stiffness(grad: np.ndarray, dx: np.ndarray, lam: float, mu: float) -> np.ndarray:
    """Element stiffness matrices of isotropic linear elasticity, in 3 × 3 blocks.

    Parameters
    ----------
    grad : (b, 3, e, q) float64
        Gradients of the ``b`` scalar basis functions at the ``q`` quadrature points of ``e`` elements.
    dx : (e, q) float64
        Quadrature weights times the Jacobian (positive).
    lam, mu : float

    Returns
    -------
    Ke : (e, b, 3, b, 3) float64
        ``Ke[e, a, i, c, j]``: the force along ``i`` on basis function ``a`` of a unit displacement along
        ``j`` of ``c``.
    """
    b, _, e, q = grad.shape
    scaled = (grad * np.sqrt(dx)).transpose(2, 3, 0, 1).reshape(e, q, 3 * b)
    A = np.matmul(scaled.transpose(0, 2, 1), scaled).reshape(e, b, 3, b, 3)  # sum_q dx G[a,i] G[c,j]
    trace = np.einsum("eaici->eac", A)
    K = lam * A + mu * A.transpose(0, 1, 4, 3, 2)
    K += mu * trace[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
    return K


def block_pattern(element_dofs: np.ndarray, n: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """The sparsity of a matrix assembled from elements, and where each element pair lands in it.

    Parameters
    ----------
    element_dofs : (b, e) int
        Scalar degrees of freedom of each element.
    n : int
        Number of scalar degrees of freedom.

    Returns
    -------
    pattern : (n, n) scipy.sparse.csr_matrix int64
        Sorted indices; ``data`` numbers the entries ``0, 1, ...``.
    where : (e, b, b) int64
        ``where[e, a, c]``: the entry of ``(element_dofs[a, e], element_dofs[c, e])``.
    """
    E = element_dofs.T.astype(np.int64)
    keys = (E[:, :, None] * n + E[:, None, :]).ravel()
    unique, where = np.unique(keys, return_inverse=True)
    rows, cols = np.divmod(unique, n)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))])
    pattern = sp.csr_matrix((np.arange(len(unique)), cols, indptr), shape=(n, n))
    return pattern, where.reshape(E.shape[0], E.shape[1], E.shape[1])


@njit(cache=True)
def _scatter_blocks(where, Ke, blocks):  # pragma: no cover - compiled
    for e in range(where.shape[0]):
        for a in range(where.shape[1]):
            for c in range(where.shape[2]):
                w = where[e, a, c]
                for i in range(3):
                    for j in range(3):
                        blocks[w, i, j] += Ke[e, a, i, c, j]


def stiffness_matrix(basis, lam: float, mu: float) -> sp.bsr_matrix:
    """The elasticity stiffness matrix on a scalar basis, in 3 × 3 blocks, assembled by chunks of elements.

    Parameters
    ----------
    basis : skfem.CellBasis
        Scalar basis (see :func:`scalar_basis`).
    lam, mu : float
        Lamé's parameters, MPa.

    Returns
    -------
    K : (3N, 3N) scipy.sparse.bsr_matrix float64
        N/mm, blocks of 3 × 3; degree of freedom ``3 s + c``.
    """
    grad = np.stack([phi[0].grad for phi in basis.basis])
    pattern, where = block_pattern(basis.element_dofs, basis.N)
    blocks = np.zeros((pattern.nnz, 3, 3))
    for lo in range(0, where.shape[0], CHUNK):
        hi = min(lo + CHUNK, where.shape[0])
        Ke = _element_stiffness(grad[:, :, lo:hi], basis.dx[lo:hi], lam, mu)
        _scatter_blocks(where[lo:hi], Ke, blocks)
    return sp.bsr_matrix((blocks, pattern.indices, pattern.indptr), shape=(3 * basis.N, 3 * basis.N))


def restrict_blocks(K: sp.bsr_matrix, keep: np.ndarray) -> sp.bsr_matrix:
    """The rows and columns of the kept nodes of a 3 × 3-block matrix.

    Parameters
    ----------
    K : (3N, 3N) scipy.sparse.bsr_matrix float64
    keep : (N,) bool

    Returns
    -------
    A : (3n, 3n) scipy.sparse.bsr_matrix float64
        ``n = keep.sum()``; blocks in the order of the kept nodes.
    """
    N = K.shape[0] // 3
    ids = sp.csr_matrix((np.arange(1, K.indices.size + 1), K.indices, K.indptr), shape=(N, N))
    sub = ids[keep][:, keep].tocsr()
    sub.sort_indices()
    n = int(keep.sum())
    return sp.bsr_matrix((K.data[sub.data - 1], sub.indices, sub.indptr), shape=(3 * n, 3 * n))


def load_vector(basis, density: np.ndarray) -> np.ndarray:
    """Consistent nodal loads of a body-force density given at the quadrature points.

    Parameters
    ----------
    basis : skfem.CellBasis
    density : (3, e, q) float64
        N/mm³ at each quadrature point of each element.

    Returns
    -------
    f : (3N,) float64
        N, degree of freedom ``3 s + c``: ``f[3 s + c] = ∫ φ_s density_c``.
    """
    phi = np.stack([np.asarray(p[0]) for p in basis.basis])  # (b, e, q)
    fe = np.einsum("beq,ceq,eq->ebc", phi, density, basis.dx)
    return np.bincount(_vector_dofs(basis.element_dofs).ravel(), fe.ravel(), minlength=3 * basis.N)


# ------------------------------------------------------------------------------------------- point search
def barycentric(nodes: np.ndarray, tets: np.ndarray, cells: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of points in given tetrahedra.

    Parameters
    ----------
    nodes : (t, 3) float64
    tets : (k, 4) int64
    cells : (q,) int64
        The tetrahedron of each point.
    points : (q, 3) float64

    Returns
    -------
    coords : (q, 4) float64
        Sum to 1; all non-negative inside the tetrahedron.
    """
    a = nodes[tets[cells, 0]]
    edges = np.swapaxes(nodes[tets[cells, 1:]] - a[:, None, :], 1, 2)  # columns b-a, c-a, d-a
    lam = np.linalg.solve(edges, (points - a)[:, :, None])[:, :, 0]
    return np.column_stack([1.0 - lam.sum(axis=1), lam])


def _containing(nodes: np.ndarray, tets: np.ndarray, points: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """(q,) int64: for each point the first candidate tetrahedron ``candidates (q, c) int64`` containing it, or -1."""
    q, c = candidates.shape
    coords = barycentric(nodes, tets, candidates.ravel(), np.repeat(points, c, axis=0)).reshape(q, c, 4)
    inside = coords.min(axis=2) >= -1e-9
    return np.where(inside.any(axis=1), candidates[np.arange(q), np.argmax(inside, axis=1)], -1)


def locate(nodes: np.ndarray, tets: np.ndarray, points: np.ndarray, neighbours: int = 16
           ) -> tuple[np.ndarray, np.ndarray]:
    """The tetrahedron containing each point; points outside the mesh go to its nearest boundary point.

    The ``neighbours`` tetrahedra with the nearest centroids are tried first, then every tetrahedron whose
    bounding box holds the point. A point in none (outside the mesh) is moved to the nearest point of the
    mesh's boundary surface (libigl's point-to-mesh distance) and takes the tetrahedron of that boundary
    triangle: the nearest tetrahedron.

    Parameters
    ----------
    nodes : (t, 3) float64
    tets : (k, 4) int64
    points : (q, 3) float64
    neighbours : int

    Returns
    -------
    cells : (q,) int64
    where : (q, 3) float64
        The points, those outside the mesh moved onto its boundary.
    """
    from scipy.spatial import cKDTree

    points = np.atleast_2d(np.asarray(points, np.float64))
    centroids = nodes[tets].mean(axis=1)
    c = min(neighbours, len(tets))
    near = cKDTree(centroids).query(points, c)[1].reshape(len(points), c)
    cells = _containing(nodes, tets, points, near)
    if (cells < 0).any():  # a long sliver's centroid may be far: every tetrahedron whose box holds the point
        corners = nodes[tets]
        lo, hi = corners.min(axis=1) - 1e-9, corners.max(axis=1) + 1e-9
        for i in np.flatnonzero(cells < 0):
            boxed = np.flatnonzero(((lo <= points[i]) & (points[i] <= hi)).all(axis=1))
            if len(boxed):
                cells[i] = _containing(nodes, tets, points[i:i + 1], boxed[None])[0]
    where = points.copy()
    outside = np.flatnonzero(cells < 0)
    if len(outside):
        import igl

        faces, owner = boundary_faces(tets)
        _, face, closest = igl.point_mesh_squared_distance(points[outside], nodes, faces)
        cells[outside] = owner[np.asarray(face, np.int64)]
        where[outside] = closest
    return cells, where


def boundary_faces(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The triangles of a tetrahedral mesh that belong to one tetrahedron only.

    Parameters
    ----------
    tets : (k, 4) int64

    Returns
    -------
    faces : (b, 3) int64
    owner : (b,) int64
        The tetrahedron of each face.
    """
    local = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
    faces = tets[:, local].reshape(-1, 3)
    owner = np.repeat(np.arange(len(tets)), 4)
    _, index, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    keep = index[counts == 1]
    return faces[keep], owner[keep]


# -------------------------------------------------------------------------------------------------- loads
def load_patch(nodes: np.ndarray, tets: np.ndarray, point: np.ndarray, radius: float | None = None
               ) -> np.ndarray:
    """The tetrahedra a point load at ``point`` is spread over.

    Parameters
    ----------
    nodes : (t, 3) float64
    tets : (k, 4) int64
    point : (3,) float64
    radius : float, optional
        The tetrahedra whose centroid is within ``radius`` mm of the point. Without it (or when none is),
        the tetrahedron containing the point (the nearest one for a point outside) and every tetrahedron
        sharing a vertex with it.

    Returns
    -------
    patch : (p,) int64
        Tetrahedron indices.
    """
    point = np.asarray(point, np.float64).reshape(3)
    if radius is not None:
        within = np.flatnonzero(np.linalg.norm(nodes[tets].mean(axis=1) - point, axis=1) <= radius)
        if len(within):
            return within
    cell = locate(nodes, tets, point[None])[0][0]
    return np.flatnonzero(np.isin(tets, tets[cell]).any(axis=1))


def point_load_density(x: np.ndarray, dx: np.ndarray, point: np.ndarray, force: np.ndarray) -> np.ndarray:
    """An affine body-force density over a patch with the resultant and the moment of a point force.

    The density is ``force / V (1 + g·(x - x̄))`` (``V`` the patch volume, ``x̄`` its centroid): it integrates
    to ``force``, and ``g = V C⁻¹ (point - x̄)`` (``C`` the patch's second moment of volume about ``x̄``) puts
    its first moment at ``point``, so it has the moment of ``force`` acting at ``point`` about any centre.

    Parameters
    ----------
    x : (3, e, q) float64
        Quadrature points of the patch's ``e`` elements, mm.
    dx : (e, q) float64
        Their weights (times the Jacobian), mm³.
    point : (3,) float64
        Where the force acts, mm.
    force : (3,) float64
        N.

    Returns
    -------
    density : (3, e, q) float64
        N/mm³ at the quadrature points.
    """
    volume = dx.sum()
    centroid = np.einsum("ceq,eq->c", x, dx) / volume
    r = x - centroid[:, None, None]
    second = np.einsum("ceq,deq,eq->cd", r, r, dx)
    g = volume * np.linalg.solve(second, np.asarray(point, np.float64) - centroid)
    shape = 1.0 + np.einsum("c,ceq->eq", g, r)
    return np.asarray(force, np.float64)[:, None, None] / volume * shape[None]


def body_force_density(basis, body_force, load_points, load_forces, load_radius) -> np.ndarray:
    """(3, k, q) float64: the body force (N/mm³) at every quadrature point, with the point loads spread."""
    k, q = basis.dx.shape
    density = np.zeros((3, k, q))
    if body_force is not None:
        density += np.asarray(body_force, np.float64).reshape(3)[:, None, None]
    if load_points is None:
        return density
    P = np.atleast_2d(np.asarray(load_points, np.float64))
    F = np.atleast_2d(np.asarray(load_forces, np.float64))
    if P.shape != F.shape or P.shape[1] != 3:
        raise ValueError(f"load_points and load_forces must both be (L, 3), got {P.shape} and {F.shape}")
    nodes, tets = basis.mesh.p.T, basis.mesh.t.T.astype(np.int64)
    x = np.asarray(basis.global_coordinates())
    for point, force in zip(P, F):
        patch = load_patch(nodes, tets, point, load_radius)
        density[:, patch] += point_load_density(x[:, patch], basis.dx[patch], point, force)
    return density


def held_nodes(basis, fixed: np.ndarray) -> np.ndarray:
    """Scalar degrees of freedom held still: the fixed vertices, the edges both ends of which are fixed,
    and the vertices of no tetrahedron.

    Parameters
    ----------
    basis : skfem.CellBasis
    fixed : (t,) bool

    Returns
    -------
    held : (N,) bool
    """
    mesh = basis.mesh
    held = np.zeros(basis.N, bool)
    held[: mesh.nvertices] = fixed
    held[: mesh.nvertices] |= np.bincount(mesh.t.ravel(), minlength=mesh.nvertices) == 0
    if basis.N > mesh.nvertices:  # P2: one degree of freedom per edge, after the vertices
        held[basis.edge_dofs[0]] = fixed[mesh.edges].all(axis=0)
    return held


def check_fixed(nodes: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """``fixed`` as a boolean mask, checked to hold the mesh against every rigid motion.

    Parameters
    ----------
    nodes : (t, 3) float64
    fixed : (t,) bool

    Returns
    -------
    fixed : (t,) bool

    Raises
    ------
    ValueError
        When no node is fixed, or all the fixed nodes lie on one line (the mesh could turn about it).
    """
    fixed = np.asarray(fixed, bool).reshape(-1)
    if fixed.shape != (len(nodes),):
        raise ValueError(f"fixed must be a (t,) bool mask over the {len(nodes)} nodes, got shape {fixed.shape}")
    if not fixed.any():
        raise ValueError("no node is fixed: nothing holds the mesh against rigid motion (fix the plate's nodes)")
    held = nodes[fixed]
    spread = np.linalg.svd(held - held.mean(axis=0), compute_uv=False) if len(held) > 1 else np.zeros(1)
    if len(spread) < 2 or spread[1] <= 1e-9 * max(float(np.ptp(nodes, axis=0).max()), 1e-300):
        raise ValueError("the fixed nodes all lie on one line: the mesh could still turn about it")
    return fixed


def prolongation(basis) -> sp.csr_matrix:
    """The P1 → P2 interpolation of a scalar field on one tetrahedral mesh.

    Parameters
    ----------
    basis : skfem.CellBasis
        The P2 scalar basis (vertices first, then edges).

    Returns
    -------
    P : (N2, t) scipy.sparse.csr_matrix float64
        A vertex keeps its value, an edge's midpoint takes the mean of its ends'.
    """
    mesh = basis.mesh
    t, e = mesh.nvertices, mesh.edges.shape[1]
    rows = np.concatenate([np.arange(t), basis.edge_dofs[0], basis.edge_dofs[0]])
    cols = np.concatenate([np.arange(t), mesh.edges[0], mesh.edges[1]])
    vals = np.concatenate([np.ones(t), np.full(2 * e, 0.5)])
    return sp.csr_matrix((vals, (rows, cols)), shape=(basis.N, t))
