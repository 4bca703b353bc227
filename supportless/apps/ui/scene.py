"""The 3D view of the viewer (viser's scene): plate, skinned mesh, overlays, skeleton, gizmo.

:class:`Scene` draws what it is given and reports clicks and drags; it knows
nothing of energies or of the editing state. The surface is a viser *skinned*
mesh, so a new pose sends only the bone frames (a few hundred bytes) and the
browser skins with the top four weights per vertex. Risky faces and
intersecting faces are drawn as overlays of the exactly posed surface.

A pose can be drawn standing or placed elsewhere, e.g. as printed: a
*placement* ``(Q, shift)`` turns the whole model, ``shown = V @ Q.T + shift``
(bone frames, joints, bones and gizmo alike); the gizmo still reports
rotations in the standing frame.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ...energies.surface import boundary_edges
from .columns import column_shell

__all__ = ["Scene", "draw_welcome", "matrix_from_quat", "placement3", "quat_from_matrix", "to3",
           "transforms3"]

# colours (RGB 0-255)
# colours (RGB 0-255): a mid-dark body on the light ground, warm overhangs on it, the skeleton darker still
MESH_COLOR = (45, 85, 135)
RISKY_COLORS = ((250, 205, 60), (245, 130, 40), (215, 35, 35))  # little / more / most support
INTERSECT_COLOR = (200, 40, 220)
SUPPORT_COLOR = (255, 160, 60)
SUPPORT_OPACITY = 0.3
BONE_FREE_COLOR = (20, 40, 90)
BONE_FIXED_COLOR = (120, 120, 120)
BONE_LOCKED_COLOR = (150, 20, 20)
BONE_SELECTED_COLOR = (255, 140, 0)
JOINT_COLOR = (20, 30, 70)
PLATE_COLOR = (200, 204, 212)
MESH_OPACITY = 0.85


# --------------------------------------------------------------------------- #
# small geometry helpers for display
# --------------------------------------------------------------------------- #
def to3(a: np.ndarray) -> np.ndarray:
    """Points in 3D: ``(..., 2)`` gets z = 0, ``(..., 3)`` is returned as is."""
    a = np.asarray(a, np.float64)
    if a.shape[-1] == 3:
        return a
    return np.concatenate([a, np.zeros(a.shape[:-1] + (1,))], axis=-1)


def transforms3(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bone transforms in 3D.

    Parameters
    ----------
    T : (m, d, d+1) float64

    Returns
    -------
    rotations : (m, 3, 3) float64
    translations : (m, 3) float64
    """
    d = T.shape[-2]
    if d == 3:
        return T[..., :3], T[..., 3]
    A = np.tile(np.eye(3), T.shape[:-2] + (1, 1))
    A[..., :2, :2] = T[..., :2]
    return A, to3(T[..., 2])


def placement3(placement) -> tuple[np.ndarray, np.ndarray]:
    """A placement in 3D.

    Parameters
    ----------
    placement : tuple of ((d, d) float64, (d,) float64) or None
        ``(Q, shift)``: ``shown = V @ Q.T + shift``; None leaves the model as it is.

    Returns
    -------
    Q3 : (3, 3) float64
        ``Q`` in the upper-left block (a planar turn is about z).
    shift3 : (3,) float64
    """
    if placement is None:
        return np.eye(3), np.zeros(3)
    Q, shift = (np.asarray(a, np.float64) for a in placement)
    d = Q.shape[0]
    Q3 = np.eye(3)
    Q3[:d, :d] = Q
    return Q3, to3(shift)


def quat_from_matrix(R: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) -> unit quaternions (..., 4) ``wxyz``, as viser takes them (a pose's bones in
    one call: viser's conversion costs about 0.2 ms a call, whatever the batch)."""
    import viser.transforms as vtf

    return np.asarray(vtf.SO3.from_matrix(R).wxyz, np.float64)


def matrix_from_quat(wxyz) -> np.ndarray:
    """Unit quaternion (4,) ``wxyz`` -> rotation matrix (3, 3)."""
    import viser.transforms as vtf

    return np.asarray(vtf.SO3(np.asarray(wxyz, np.float64)).as_matrix(), np.float64)


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) turning the direction of ``a`` onto that of ``b``."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(a @ b)
    if c < -1 + 1e-9:
        axis = np.cross(a, [1.0, 0, 0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(a, [0, 1.0, 0])
        axis /= np.linalg.norm(axis)
        return 2 * np.outer(axis, axis) - np.eye(3)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1 + c)


def _perpendicular(up: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to ``up`` (3,)."""
    ref = np.array([1.0, 0, 0]) if abs(up[0]) < 0.9 else np.array([0, 0, 1.0])
    v = ref - (ref @ up) * up
    return v / np.linalg.norm(v)


def support_levels(V3: np.ndarray, F: np.ndarray, up: np.ndarray, risky: np.ndarray) -> np.ndarray:
    """How much support each risky face needs, in three levels for colouring.

    Parameters
    ----------
    V3 : (n, 3) float64
    F : (f, 3) int64
    up : (3,) float64
    risky : (f,) bool

    Returns
    -------
    levels : (f,) int64
        0, 1 or 2 by steepness times height above the lowest face, in thirds
        of the largest among the risky faces; 0 where not risky (only the risky faces are measured).
    """
    levels = np.zeros(len(F), np.int64)
    r = np.flatnonzero(risky)
    if not len(r):
        return levels
    h = (V3 @ up)[F].sum(axis=1) / 3.0  # each face's centre's height
    a, b, c = V3[F[r, 0]], V3[F[r, 1]], V3[F[r, 2]]
    n = np.cross(b - a, c - a)
    steep = np.abs(n @ up) / np.maximum(np.linalg.norm(n, axis=1), 1e-30)
    need = steep * (h[r] - h.min())
    levels[r] = np.digitize(need / max(float(need.max()), 1e-30), [1 / 3, 2 / 3])
    return levels


def draw_welcome(server, text: str) -> None:
    """The empty scene before a model is open: a plate, and what to do in words."""
    s = server.scene
    s.set_up_direction("+z")
    s.add_grid("/plate", width=200.0, height=200.0, plane="xy", cell_size=10.0, section_size=50.0,
               cell_color=(190, 195, 205), section_color=(120, 125, 140), plane_color=PLATE_COLOR, plane_opacity=0.8)
    s.add_label("/welcome", text, position=(0.0, 0.0, 20.0))
    cam = server.initial_camera
    cam.look_at, cam.position, cam.up = (0.0, 0.0, 10.0), (0.0, -220.0, 140.0), (0.0, 0.0, 1.0)


# --------------------------------------------------------------------------- #
# the scene
# --------------------------------------------------------------------------- #
class Scene:
    """Everything drawn in the 3D view of one rig.

    Parameters
    ----------
    server : viser.ViserServer
    rig : supportless.rig.rig.Rig
    on_joint_click : callable
        ``on_joint_click(joint)`` (0-based) when a joint is clicked.
    on_gizmo : callable
        ``on_gizmo(phase, rotation)`` while the rotation gizmo is dragged:
        ``phase`` is ``"start"``, ``"update"`` or ``"end"``, ``rotation``
        (3, 3) float64 its orientation in the world of the standing model
        (the placement the pose is drawn with taken back).
    scale : float
        Scene units per model unit: the print frame's millimetres per unit, so
        every model is drawn at its printed size whatever its file's units
        (a 79 m glTF fox printed 60 mm tall is 60 units tall in the view).
    mesh_key : int
        Names the skinned surface's node (``/surface/KEY``): each model opened in one page has its own
        (see :meth:`close`).

    Attributes
    ----------
    size : float
        The rest pose's bounding-box diagonal, scene units.
    """

    def __init__(self, server, rig, on_joint_click: Callable[[int], None],
                 on_gizmo: Callable[[str, np.ndarray], None], scale: float = 1.0, mesh_key: int = 0):
        self.server = server
        self.rig = rig
        self.scale = float(scale)
        self.up = to3(rig.up)
        self.faces = np.asarray(rig.faces, np.int64)
        self.edges = np.asarray(boundary_edges(self.faces), np.int64) if rig.dim == 2 else None
        rest = self.scale * to3(rig.vertices)
        self.roots = self.scale * to3(rig.joints[rig.pivots])  # the joint each bone turns about
        self.size = float(np.linalg.norm(np.ptp(rest, axis=0)))
        centre = rest.mean(axis=0)
        self._centre_plate = centre - (centre @ self.up) * self.up
        self.h_weights = None
        self.h_risky_edges = None
        self._turn = np.eye(3)  # the placement's rotation the pose is drawn with
        self._overlays: dict = {}
        s = server.scene
        self._add_plate(s, float((rest @ self.up).min()))
        m = rig.bone_count
        self.h_mesh = s.add_mesh_skinned(
            f"/surface/{mesh_key}", rest.astype(np.float32), self.faces,
            bone_wxyzs=np.tile([1.0, 0, 0, 0], (m, 1)), bone_positions=self.roots,
            skin_weights=np.asarray(rig.weights, np.float64), color=MESH_COLOR, opacity=MESH_OPACITY,
            side="double" if rig.dim == 2 else "front", flat_shading=False)
        self._add_skeleton(s, on_joint_click, on_gizmo)
        self._place_camera(centre, rest)

    # ----------------------------------------------------------------- build
    def _add_plate(self, s, lo: float) -> None:
        up, size = self.up, self.size
        axis = int(np.argmax(np.abs(up)))
        if np.allclose(np.abs(up), np.eye(3)[axis]):
            s.set_up_direction(("+" if up[axis] > 0 else "-") + "xyz"[axis])
        else:
            s.set_up_direction(tuple(up))
        step = 10 ** np.floor(np.log10(size / 3))
        self.h_grid = s.add_grid("/plate", width=3 * size, height=3 * size, plane="xy", cell_size=step,
                                 section_size=step * 5,
                                 wxyz=quat_from_matrix(_rotation_between(np.array([0, 0, 1.0]), up)),
                                 position=self._centre_plate + lo * up, cell_color=(190, 195, 205),
                                 section_color=(120, 125, 140), plane_color=PLATE_COLOR, plane_opacity=0.8,
                                 shadow_opacity=0.2)
        side = _perpendicular(up)
        back = -np.cross(up, side)
        a0 = self._centre_plate + lo * up + 0.55 * size * (back - side)
        s.add_arrows("/up_arrow", points=np.array([[a0, a0 + 0.3 * size * up]]), colors=(20, 160, 60),
                     shaft_radius=0.005 * size, head_radius=0.015 * size, head_length=0.045 * size)
        s.add_label("/up_label", "up", position=a0 + 0.34 * size * up)

    def _add_skeleton(self, s, on_joint_click, on_gizmo) -> None:
        rig, size = self.rig, self.size
        J = self.scale * to3(rig.joints)
        self.h_joints = []
        for j, p in enumerate(J):
            h = s.add_icosphere(f"/model/joints/{j}", radius=0.011 * size, color=JOINT_COLOR, position=p,
                                subdivisions=2)
            h.on_click(lambda _event, j=j: on_joint_click(j))
            self.h_joints.append(h)
        self.h_bones = s.add_line_segments("/model/bones", points=J[rig.bones],
                                           colors=np.broadcast_to(np.uint8(BONE_FREE_COLOR), (len(rig.bones), 2, 3)),
                                           thickness=0.006 * size)
        self.h_gizmo = s.add_transform_controls("/gizmo", scale=0.3 * size, disable_axes=True,
                                                disable_sliders=True, depth_test=False, position=self.roots[0])

        @self.h_gizmo.on_update
        async def _(event):  # async: the phases arrive in order
            phase = event.phase if event.phase in ("start", "end") else "update"
            on_gizmo(phase, self._turn.T @ matrix_from_quat(event.target.wxyz))

    def _place_camera(self, centre: np.ndarray, rest: np.ndarray) -> None:
        """Look at the model's broad side (across its longer horizontal extent), a little from above: from the
        front of a figure made +Y up facing +Z (glTF) or +Z up facing -Y (CAD), the conventions' front."""
        up = self.up
        side = _perpendicular(up)
        front = np.cross(side, up)
        if np.ptp(rest @ front) > np.ptp(rest @ side):  # longer along "front": look along "side" instead
            side, front = front, -side
        cam = self.server.initial_camera
        cam.look_at = tuple(centre)
        cam.position = tuple(centre + self.size * (0.9 * front + 0.3 * side + 0.45 * up))
        cam.up = tuple(up)
        cam.near = 1e-3 * self.size  # the clipping planes follow the model's size, whatever its units
        cam.far = 100.0 * self.size
        for client in self.server.get_clients().values():  # a page already open moves to the new model
            try:
                c = client.camera
                c.near, c.far = cam.near, cam.far
                c.up_direction = tuple(up)
                c.position, c.look_at = cam.position, cam.look_at
            except Exception:  # noqa: BLE001 - a page that is closing keeps its camera
                pass

    def close(self) -> None:
        """Take this model out of the view, for another scene to be drawn in its place.

        The skinned surface is hidden, not removed: viser's page fails (a script error) when a skinned mesh
        is removed, so each model's surface has a node of its own; everything else is removed or replaced.
        """
        self.h_mesh.visible = False
        self.server.scene.remove_by_name("/model")

    # ------------------------------------------------------------------ draw
    def set_opacity(self, opacity: float) -> None:
        """Mesh opacity in (0, 1]; 1 draws it opaque."""
        self.h_mesh.opacity = opacity if opacity < 0.999 else None

    def draw_pose(self, angles: np.ndarray, selected: int, fixed: np.ndarray, move_gizmo: bool = True,
                  placement=None, locked: np.ndarray | None = None) -> None:
        """Send the bone frames, joints and bones of a pose (sent at once, then flushed).

        Parameters
        ----------
        angles : (m, 3) float64
        selected : int
            The bone drawn in orange, where the gizmo sits.
        fixed : (m,) bool
            Bones drawn grey (fixed in the search); the others dark blue.
        locked : (m,) bool, optional
            Bones the user locked, drawn dark red.
        move_gizmo : bool
            False while the gizmo is being dragged.
        placement : tuple of ((d, d) float64, (d,) float64), optional
            ``(Q, shift)``: draw the pose turned by ``Q`` and moved by
            ``shift`` (``shown = V @ Q.T + shift``), e.g. as printed; None
            draws it standing.
        """
        rig, k = self.rig, self.scale
        P, s = placement3(placement)
        Q, t = transforms3(rig.transforms(angles))
        pos = (np.einsum("bij,bj->bi", Q, self.roots) + k * t) @ P.T + k * s
        Q = np.einsum("ij,bjk->bik", P, Q)
        J = k * (to3(rig.posed_joints(angles)) @ P.T + s)
        self._turn = P
        colors = np.where(fixed[:, None], np.uint8(BONE_FIXED_COLOR), np.uint8(BONE_FREE_COLOR)).astype(np.uint8)
        if locked is not None:
            colors[locked] = BONE_LOCKED_COLOR
        colors[selected] = BONE_SELECTED_COLOR
        wxyz = quat_from_matrix(Q)
        with self.server.atomic():
            for b, bone in enumerate(self.h_mesh.bones):
                bone.wxyz = wxyz[b]
                bone.position = pos[b]
            for j, h in enumerate(self.h_joints):
                h.position = J[j]
            self.h_bones.points = J[rig.bones].astype(np.float32)
            self.h_bones.colors = np.repeat(colors[:, None], 2, axis=1)
            if move_gizmo:
                self.h_gizmo.position = pos[selected]
                self.h_gizmo.wxyz = wxyz[selected]
        self.server.flush()

    def draw_overlays(self, vertices: np.ndarray, risky: np.ndarray | None, intersecting: np.ndarray | None,
                      weights_of: int | None = None) -> None:
        """Move the plate under the posed surface and draw its overlays.

        Parameters
        ----------
        vertices : (n, d) float64
            The exactly posed surface, placed as :meth:`draw_pose` placed the pose.
        risky : (f,) bool or None
            Faces (boundary edges in 2D) needing support; None hides them.
        intersecting : (k,) int64 or None
            Faces that intersect another face (3D).
        weights_of : int, optional
            Colour the surface by this bone's skinning weights instead.
        """
        V3 = self.scale * to3(vertices)
        lo = float((V3 @ self.up).min())
        self.h_grid.position = self._centre_plate + (lo - 1e-4 * self.size) * self.up
        self._draw_weights(V3, weights_of)
        if self.rig.dim == 2:
            self._draw_risky_edges(V3, risky)
            return
        F = self.faces
        risky = np.zeros(len(F), bool) if risky is None else risky
        level = support_levels(V3, F, self.up, risky)
        with self.server.atomic():
            for k in range(3):
                self._overlay(f"risky{k}", self._lifted(V3, np.flatnonzero(risky & (level == k)), 1.0),
                              RISKY_COLORS[k])
            self._draw_crossings(V3, intersecting)

    def draw_crossings(self, vertices: np.ndarray, intersecting: np.ndarray | None) -> None:
        """Only the faces that intersect another face (3D), as :meth:`draw_overlays` draws them: the app draws the
        exact crossings after the rest of a pose's overlays.

        Parameters
        ----------
        vertices : (n, 3) float64
            As :meth:`draw_overlays`.
        intersecting : (k,) int64 or None
        """
        self._draw_crossings(self.scale * to3(vertices), intersecting)

    def _draw_crossings(self, V3: np.ndarray, intersecting: np.ndarray | None) -> None:
        faces = np.zeros(0, np.int64) if intersecting is None else np.unique(np.asarray(intersecting, np.int64))
        self._overlay("intersections", self._lifted(V3, faces, 1.5), INTERSECT_COLOR, side="double")

    def _lifted(self, V3: np.ndarray, faces: np.ndarray, k: float) -> np.ndarray:
        """(3 len(faces), 3) float64: the corners of ``faces`` (s,) int64 of the scaled surface ``V3``, lifted off it
        along their normals by ``k`` times a small share of the model's size, so they show on top."""
        a, b, c = (V3[self.faces[faces, i]] for i in range(3))
        n = np.cross(b - a, c - a)
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        return (np.stack([a, b, c], 1) + k * 0.002 * self.size * n[:, None, :]).reshape(-1, 3)

    def draw_faces(self, key: str, vertices: np.ndarray, mask: np.ndarray | None, color, lift: float = 2.0) -> None:
        """Some faces of the posed surface in one colour, lifted off it to show on top (3D).

        Parameters
        ----------
        key : str
            The overlay's name: one node per key, reused from one pose to the next.
        vertices : (n, 3) float64
            The exactly posed surface, placed as :meth:`draw_pose` placed the pose (model units).
        mask : (f,) bool or None
            The faces drawn; None (or none set) hides the overlay.
        color : tuple of int
            RGB, 0-255.
        lift : float
            How far off the surface, in 0.2 % of the model's size (risky faces 1, intersecting faces 1.5).
        """
        if mask is None or not np.any(mask):
            self._overlay(key, np.zeros((0, 3)), color)
            return
        V3 = self.scale * to3(vertices)
        a, b, c = (V3[self.faces[mask, k]] for k in range(3))
        n = np.cross(b - a, c - a)
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        self._overlay(key, (np.stack([a, b, c], 1) + lift * 0.002 * self.size * n[:, None, :]).reshape(-1, 3), color)

    def draw_support(self, columns) -> None:
        """The predicted support as a translucent body: the outer surface of the ray grid's columns
        (:func:`.columns.column_shell`; no walls between neighbours to blend through).

        Parameters
        ----------
        columns : tuple or None
            :func:`supportless.energies.support.support_columns` of the shown
            surface (model units): ``(bottoms, heights, cell, basis)``; None hides it.
        """
        if columns is None or len(columns[1]) == 0:
            self._overlay("support", np.zeros((0, 3)), SUPPORT_COLOR)
            return
        bottoms, heights, cell, basis = columns
        V, F = column_shell(self.scale * np.asarray(bottoms), self.scale * np.asarray(heights), self.scale * cell,
                            basis)
        self._overlay("support", V[F].reshape(-1, 3), SUPPORT_COLOR, opacity=SUPPORT_OPACITY)

    def _draw_weights(self, V3: np.ndarray, bone: int | None) -> None:
        """A copy of the posed surface coloured by one bone's weights, or the skinned mesh."""
        if bone is None:
            if self.h_weights is not None:
                self.h_weights.remove()
                self.h_weights = None
            self.h_mesh.visible = True
            return
        import trimesh
        from matplotlib import colormaps

        rgba = (colormaps["viridis"](np.asarray(self.rig.weights[:, bone])) * 255).astype(np.uint8)
        mesh = trimesh.Trimesh(V3, self.faces, vertex_colors=rgba, process=False)
        self.h_weights = self.server.scene.add_mesh_trimesh("/model/weights", mesh)
        self.h_mesh.visible = False

    def _draw_risky_edges(self, V3: np.ndarray, risky: np.ndarray | None) -> None:
        h = self.h_risky_edges
        if risky is None or not risky.any():
            if h is not None:
                h.visible = False
            return
        pts = V3[self.edges[risky]].astype(np.float32)
        cols = np.broadcast_to(np.asarray(RISKY_COLORS[2], np.uint8), pts.shape).copy()
        if h is None:
            self.h_risky_edges = self.server.scene.add_line_segments("/model/risky_edges", pts, colors=cols,
                                                                     thickness=0.01 * self.size)
            return
        with self.server.atomic():
            h.points, h.colors, h.visible = pts, cols, True

    def _overlay(self, key: str, tri: np.ndarray, color, side: str = "front", opacity: float | None = None) -> None:
        """Show triangles ``tri`` (3k, 3) as a single-colour overlay node, reusing the node."""
        h = self._overlays.get(key)
        if len(tri) == 0:
            if h is not None and h.visible:
                h.visible = False
            return
        V = np.ascontiguousarray(tri, np.float32)
        F = np.arange(len(V), dtype=np.uint32).reshape(-1, 3)
        if h is None:
            self._overlays[key] = self.server.scene.add_mesh_simple(f"/model/{key}", V, F, color=color,
                                                                    flat_shading=True, side=side, opacity=opacity)
            return
        h.vertices = V  # fresh arrays: viser sends what changed
        if len(h.faces) != len(F):
            h.faces = F
        if not h.visible:
            h.visible = True
