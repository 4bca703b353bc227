"""The control panel of the viewer (viser's GUI): energies, pose, search, files.

:class:`Panel` builds the widgets, sends what the user does to the app's
actions and shows what the app gives it. Its search settings start at the
state's :class:`~supportless.search.settings.SearchSettings` (by default the tool's
defaults), so the page has no defaults of its own.
"""

from __future__ import annotations

import numpy as np

from ...search.objective import INFEASIBLE, OVERHANG_MODELS
from ...search.settings import ORIENT_MODES, RANGES, SearchSettings
from .opener import MODEL_SUFFIXES, SKELETON_SUFFIXES
from .readout import filament_text, volume_text
from .scene import MESH_OPACITY

__all__ = ["NUMBER_SETTINGS", "Panel", "SLICERS", "VIEWS", "drop_zone_html", "lead_markdown", "measures_markdown",
           "turn_text"]

#: The slicers the Slice folder offers: label -> (engine, support), as ``--slicer`` and ``--support``.
SLICERS = {"PrusaSlicer": ("prusa", "grid"), "Cura": ("cura", "grid"), "Cura, tree supports": ("cura", "tree")}

#: The view choices of the panel: label -> frame (:data:`supportless.apps.ui.state.FRAMES`).
VIEWS = {"standing": "standing", "as printed": "print"}

#: The numeric search settings in the panel: field, label, step (their limits are the settings' own RANGES).
_FIELDS = (
    ("particles", "Particles", 1),
    ("iterations", "Iterations", 1),
    ("seed", "Seed", 1),
    ("joint_limit", "Joint limit °", 1.0),
    ("w_arap", "w ARAP", 0.1),
    ("w_overhang", "w overhang", 0.1),
    ("w_intersect", "w intersect", 1.0),
    ("overhang_angle", "Overhang angle °", 1.0),
    ("overhang_margin", "Overhang margin °", 1.0),
)
NUMBER_SETTINGS = tuple((name, label, {"step": step} | {key: bound for key, bound in zip(("min", "max"), RANGES[name])
                                                          if bound is not None})
                        for name, label, step in _FIELDS)


def _fmt(x: float | None, spec: str = ".4g") -> str:
    return "n/a" if x is None else format(float(x), spec)


def _vs_rest(x: float | None) -> str:
    if x is None:
        return "rest pose needs none"
    return f"{x:.1f} % less than rest" if x >= 0 else f"{-x:.1f} % more than rest"


def _vector(v) -> str:
    return "(" + ", ".join(f"{x:.2f}" for x in np.asarray(v, np.float64) + 0.0) + ")"


def turn_text(m: dict) -> str:
    """How the pose is printed, from :meth:`~supportless.apps.ui.state.EditorState.measure`'s
    ``turn_deg``, ``turn_axis`` ((3,) or None in 2D) and ``print_direction`` ((d,))."""
    if abs(m["turn_deg"]) < 0.05:
        return "as it stands (not turned)"
    about = "counter-clockwise" if m["turn_axis"] is None else f"about {_vector(m['turn_axis'])}"
    return (f"turned {m['turn_deg']:.1f}° {about}; the model's {_vector(m['print_direction'])} "
            f"printed upward")


def lead_markdown(lead: dict | None) -> list[str]:
    """The panel's first line: the support filament (:func:`supportless.apps.ui.filament.support_lead`), in words.

    The slicer's figure when a Slice measured this pose (the estimate beside it), else the estimate the command
    line's summary prints, labelled as one; nothing for a planar rig (None).
    """
    if lead is None:
        return []
    figure, vs = filament_text(lead["mm"], lead["g"]), _vs_rest(lead["reduction_percent"])
    estimate = lead.get("estimate")
    if estimate is not None:
        return [f"- Support filament, sliced by {lead['source']}: **{figure}** ({vs}) · the estimate: "
                f"{filament_text(estimate['mm'], estimate['g'])}"]
    other = "; the last Slice was of another pose" if lead.get("other_slice") else ""
    return [f"- Support filament, an estimate: **{figure}** ({vs}) · predicted for PrusaSlicer, printed "
            f"{lead['height_mm']:.4g} mm tall, as the command line's summary says (Slice measures it{other})"]


def measures_markdown(m: dict, settings: SearchSettings, latency: dict, dim: int, scale: float = 1.0,
                      rules: list[str] | None = None, lead: dict | None = None) -> str:
    """The energies list of the panel.

    Parameters
    ----------
    m : dict
        :meth:`supportless.apps.ui.state.EditorState.measure` of the pose.
    settings : SearchSettings
        The settings that objective belongs to (weights, thresholds).
    latency : dict
        ``mesh`` and ``full`` update times, ms, and ``exact`` once the crossings are found.
    dim : int
        2 for a planar rig.
    scale : float
        Millimetres per model unit (the print frame's): support volumes are shown printed, mm³ and grams.
    rules : list of str, optional
        The hard rules the pose breaks (:func:`supportless.apps.ui.readout.broken_rules`), said under the objective.
    lead : dict, optional
        The support filament the list leads with (:func:`supportless.apps.ui.filament.support_lead`); the
        preview's column volume follows it as its own line, its grams left out (a slicer lays down less).
    """
    t = m["terms"]
    inter = m.get("intersecting_faces")
    inter_txt = ("not checked (2D)" if dim == 2 else "checking…" if inter is None
                 else f"{len(inter)} faces" + (" (magenta)" if len(inter) else ""))
    red = m.get("reduction", {})
    turned = abs(m["turn_deg"]) >= 0.05
    up = m["upright"]
    vol = (lambda v: volume_text(v, scale, with_grams=lead is None)) if dim == 3 else _fmt
    column = vol(m["support_column"]) if lead is not None else f"**{vol(m['support_column'])}**"
    standing = ([f"- Standing (not turned): support (columns) {vol(up['support_column'])} · "
                 f"{int(np.sum(m['risky_standing']))} risky faces"] if turned else [])
    broken = [f"- ⚠ Breaks a rule (the objective adds {INFEASIBLE:g} while it does): {rule}" for rule in rules or ()]
    return "\n".join([
        *lead_markdown(lead),
        f"- Support columns (the preview's, solid, as printed): {column} ({_vs_rest(red.get('support_column'))})",
        f"- Support (prism estimate): {vol(m['support_prism'])} ({_vs_rest(red.get('support_prism'))})",
        f"- Printed: {turn_text(m)}" + ("; support counted as printed" if turned else ""),
        f"- Risky faces (past {m['overhang_angle']:.3g}°): {int(np.sum(m['risky']))} · "
        f"self-intersecting: {inter_txt}",
        *standing,
        f"- Objective: **{_fmt(m['objective'])}** (what Optimize minimises)",
        *broken,
        f"- ARAP term: {_fmt(t['arap'])} (× {settings.w_arap:g}) · overhang term: {_fmt(t['overhang'])} "
        f"(× {settings.w_overhang:g}, faces past {settings.search_overhang_angle:.3g}°) · intersection term: "
        f"{_fmt(t['intersection'])} (× {settings.w_intersect:g})",
        f"- Update time: mesh {latency.get('mesh', 0):.1f} ms · with energies {latency.get('full', 0):.1f} ms"
        + (f" · crossings {latency['exact']:.1f} ms" if "exact" in latency else ""),
    ])


#: The page's side of a drop: each file dropped anywhere on the page goes through the Open model button's own
#: file input, one after another (a skeleton first, so the mesh after it opens with it). viser offers no drop
#: target and renders its HTML widget's markup as it is, so a broken image's error handler installs it, once.
_DROP_SCRIPT = """(function(){if(window.__slDrop)return;window.__slDrop=true;
const wait=t=>new Promise(r=>setTimeout(r,t));const sel='input[type=file][accept="%(accept)s"]';
document.addEventListener('dragover',e=>{if(e.dataTransfer&&[...e.dataTransfer.types].includes('Files')){
e.preventDefault();document.body.classList.add('sl-drag');}});
document.addEventListener('dragleave',()=>document.body.classList.remove('sl-drag'));
document.addEventListener('drop',async e=>{document.body.classList.remove('sl-drag');
if(!e.dataTransfer||!e.dataTransfer.files.length)return;e.preventDefault();
const tgf=f=>f.name.toLowerCase().endsWith('.tgf');
const files=[...e.dataTransfer.files].sort((a,b)=>tgf(b)-tgf(a));
for(const f of files){const input=document.querySelector(sel);if(!input)return;
const button=document.getElementById(input.id.replace('file_upload_',''));
const dt=new DataTransfer();dt.items.add(f);input.files=dt.files;
input.dispatchEvent(new Event('change',{bubbles:true}));await wait(300);
for(let i=0;i<6000&&button&&button.disabled;i++)await wait(100);await wait(300);}});})();"""


def drop_zone_html(accept: str, kinds: str) -> str:
    """The drop zone of the Open model folder, whose script sends dropped files through the upload button whose
    file input accepts ``accept`` (the Open model button's own list)."""
    script = (_DROP_SCRIPT % {"accept": accept}).replace("\n", "").replace('"', "&quot;")
    return (f'<div id="supportless-dropzone" style="border:2px dashed #5a6b85;border-radius:6px;padding:10px;'
            f'margin:4px 8px;color:#1d2a3a;font-size:0.9em;text-align:center">'
            f'Drop a model anywhere on this page: {kinds}; a mesh with its .tgf skeleton (both at once)'
            f'<img alt="" src="data:image/gif;base64,AA" style="display:none" onerror="{script}"></div>'
            '<style>body.sl-drag #supportless-dropzone{background:#dce8f7;border-color:#1f5fbf}</style>')


class Panel:
    """The widgets of the page's side panel.

    Parameters
    ----------
    gui : viser.GuiApi
    app : supportless.apps.ui.app.App
        Receives the actions (``undo``, ``start_optimize``, ``save_pose``...).
    previous : Panel, optional
        The panel of the model shown before, whose status line and Open model folder this one keeps.

    Attributes
    ----------
    settings : dict of str -> viser GUI handle
        The search-settings widgets, by :class:`SearchSettings` field.
    invalid : dict of str -> str
        Settings whose value in the panel the state refused, and why.
    status, measures, bone_info, fixed_info, search_info : viser markdown handles
    sliders : list of viser slider handles
        X, Y, Z angle of the selected bone, degrees.
    view : viser dropdown handle
        Show the model standing or as printed (a label of :data:`VIEWS`).
    """

    def __init__(self, gui, app, previous: Panel | None = None):
        self.gui = gui
        self.app = app
        self.rig = app.rig
        self._folders: list = []
        if previous is None:
            gui.configure_theme(control_width="large", dark_mode=False)
            self.status = gui.add_markdown("**Status:** ready")
            self._add_open_folder()
        else:  # the status line and the Open model folder stay (an upload in flight keeps its button)
            self.status, self.upload_model = previous.status, previous.upload_model
        if self.rig is None:  # nothing open yet: the page invites a model
            return
        self.names = self.rig.bone_names()
        with self._folder("Energies"):
            self.measures = gui.add_markdown("computing…")
        self._add_pose_folder()
        self._add_search_folder(app.state.settings)
        self._add_slice_folder()
        self._add_front_folder()
        self._add_files_folder()

    def close(self) -> None:
        """Remove the folders of this model (the status line and the Open model folder stay for the next)."""
        for folder in self._folders:
            folder.remove()
        self._folders.clear()

    # ----------------------------------------------------------------- build
    def _folder(self, label: str, **options):
        """A folder of this model's, removed by :meth:`close`."""
        folder = self.gui.add_folder(label, **options)
        self._folders.append(folder)
        return folder

    def _add_open_folder(self) -> None:
        g, app = self.gui, self.app
        kinds = ", ".join(MODEL_SUFFIXES)
        accept = ",".join(MODEL_SUFFIXES + SKELETON_SUFFIXES)
        with g.add_folder("Open model", expand_by_default=self.rig is None):
            self.upload_model = g.add_upload_button(
                "Open model…", icon=None, mime_type=accept,
                hint="A rigged glTF (.glb, or .gltf with its buffers inside), or a mesh: send its .tgf skeleton "
                     "first (or drop both at once); a mesh alone gets a skeleton built from its shape")
            g.add_html(drop_zone_html(accept, kinds))
        self.upload_model.on_upload(lambda _e: app.receive_upload(self.upload_model.value.name,
                                                                  self.upload_model.value.content))

    def _add_pose_folder(self) -> None:
        g, app = self.gui, self.app
        with self._folder("Pose"):
            self.bone = g.add_dropdown("Bone", self.names, initial_value=self.names[0],
                                       hint="Bone to rotate; you can also click a joint")
            self.sliders = []
            for i, label in enumerate(("X°", "Y°", "Z°")):
                sl = g.add_slider(label, min=-180.0, max=180.0, step=1.0, initial_value=0.0,
                                  disabled=self.rig.dim == 2 and i < 2,
                                  hint="Euler angle of the selected bone relative to its parent")
                sl.on_update(self._slider_moved(i))
                self.sliders.append(sl)
            g.add_button("Undo").on_click(lambda _e: app.undo())
            g.add_button("Redo").on_click(lambda _e: app.redo())
            g.add_button("Reset to rest pose").on_click(lambda _e: app.reset())
            g.add_button("Print as it stands", hint="Drop the print rotation (keep the pose)").on_click(
                lambda _e: app.print_upright())
            self.lock = g.add_checkbox("Lock this bone", False,
                                       hint="Optimize and the front keep a locked bone as it is (drawn dark red); "
                                            "saved with the pose")
            before = g.add_checkbox("Show the rest pose (before)", False,
                                    hint="Flip between the rest pose and the current one; nothing is changed")
            show_support = g.add_checkbox("Show predicted support", True,
                                          hint="Translucent orange columns: the support the estimate predicts under "
                                               "the pose as shown")
            show_strength = g.add_checkbox("Show weak sections", False,
                                           hint="Cyan: where a 2 N grip at a hand, the head or a tail breaks the pose "
                                                "as printed (pale cyan: less than twice over); the weakest is named "
                                                "under the measures")
            self.view = g.add_dropdown("View", tuple(VIEWS), initial_value="standing",
                                       hint="standing: as the model stands (the bones are edited here); "
                                            "as printed: turned by the print rotation onto the plate")
            show_risky = g.add_checkbox("Show risky faces", True)
            weights = g.add_checkbox("Colour by bone weights", False,
                                     hint="Colour the mesh by the selected bone's skinning weights")
            opacity = g.add_slider("Mesh opacity", min=0.1, max=1.0, step=0.05, initial_value=MESH_OPACITY)
            self.bone_info = g.add_markdown("")

        @self.bone.on_update
        def _(event):
            if event.client is not None:
                app.state.select_bone(self.names.index(self.bone.value))

        @self.view.on_update
        def _(event):
            if event.client is not None:
                app.set_view(frame=VIEWS[self.view.value])

        @self.lock.on_update
        def _(event):
            if event.client is not None:
                app.lock_bone(app.state.selected, bool(self.lock.value))

        before.on_update(lambda _e: app.set_view(before=bool(before.value)))
        show_support.on_update(lambda _e: app.set_view(show_support=bool(show_support.value)))
        show_strength.on_update(lambda _e: app.set_view(show_strength=bool(show_strength.value)))
        show_risky.on_update(lambda _e: app.set_view(show_risky=bool(show_risky.value)))
        weights.on_update(lambda _e: app.set_view(weights=bool(weights.value)))
        opacity.on_update(lambda _e: app.set_view(opacity=float(opacity.value)))

    def _slider_moved(self, axis: int):
        def on_update(event):
            if event.client is not None:  # moved in the page, not by the server
                self.app.on_slider(axis, float(self.sliders[axis].value))
        return on_update

    def _add_search_folder(self, settings: SearchSettings) -> None:
        g, app = self.gui, self.app
        with self._folder("Optimize"):
            self.settings = {name: g.add_number(label, getattr(settings, name), **limits)
                             for name, label, limits in NUMBER_SETTINGS}
            self.settings["overhang_model"] = g.add_dropdown(
                "Support model", OVERHANG_MODELS, initial_value=settings.overhang_model,
                hint="prism: the paper's estimate; column: columns down to the plate")
            self.settings["orient"] = g.add_dropdown(
                "Orientation", ORIENT_MODES, initial_value=settings.orient,
                hint="free: search the print orientation with the pose; keep: print as the model stands")
            self.settings["fix"] = g.add_text("Fix bones", ",".join(settings.fix),
                                              hint="1-based bone numbers, e.g. 1,4 or 'all'")
            self.settings["free"] = g.add_text("Free bones", ",".join(settings.free),
                                               hint="1-based bone numbers to free, or 'all'")
            self.fixed_info = g.add_markdown("")
            self.optimize = g.add_button("Optimize", color="green")
            self.cancel = g.add_button("Cancel search", color="red", disabled=True)
            self.progress = g.add_progress_bar(0.0)
            self.search_info = g.add_markdown("idle")
        self.invalid: dict[str, str] = {}  # setting -> why the state did not take the panel's value
        for name, h in self.settings.items():
            h.on_update(self._setting_edited(name))
        self.optimize.on_click(lambda _e: app.start_optimize())
        self.cancel.on_click(lambda _e: app.state.cancel_optimize())

    def _add_slice_folder(self) -> None:
        g, app = self.gui, self.app
        with self._folder("Slice", expand_by_default=False):
            self.slicer = g.add_dropdown("Slicer", tuple(SLICERS), initial_value=next(iter(SLICERS)),
                                         hint="The slicer run on the rest pose and the current pose, as printed")
            self.slice = g.add_button("Slice rest pose and this pose", color="blue",
                                      hint="Runs the slicer four times in the background (with and without support)")
            self.cancel_slice = g.add_button("Cancel slicing", disabled=True)
            self.slice_info = g.add_markdown("Not sliced yet: the figures of a real slicer (support filament, grams, "
                                             "added print time) appear here.")
        self.slice.on_click(lambda _e: app.start_slice(SLICERS[self.slicer.value]))
        self.cancel_slice.on_click(lambda _e: app.cancel_slice())

    def show_slicing(self, running: bool, text: str | None = None) -> None:
        """Slice / Cancel enabled as a slice runs or not, and the figures (markdown) when given."""
        self.slice.disabled = running
        self.cancel_slice.disabled = not running
        if text is not None:
            self.slice_info.content = text

    def _add_front_folder(self) -> None:
        g, app = self.gui, self.app
        with self._folder("Front", expand_by_default=False):
            self.front_count = g.add_slider("Poses", min=2, max=9, step=1, initial_value=5)
            self.find_front = g.add_button("Find front",
                                           hint="Poses from least support to least distortion (about 3 searches)")
            self.front_pose = g.add_slider("Front pose", min=1, max=2, step=1, initial_value=1, disabled=True)
            self.front_info = g.add_markdown("no front yet")
        self.find_front.on_click(lambda _e: app.start_front(int(self.front_count.value)))
        self.front_pose.on_update(lambda e: app.show_front_pose(int(self.front_pose.value) - 1)
                                  if e.client is not None else None)

    def show_front(self, front) -> None:
        """The slider over the front's poses, and their measures."""
        n = len(front.poses)
        self.find_front.disabled = False
        self.front_pose.max = max(n, 2)
        self.front_pose.disabled = n == 0
        self.front_info.content = "\n".join(
            [f"{n} poses, least support first ({front.seconds:.0f} s):"]
            + [f"- {k}: support {p.support:.4g}, distortion {p.distortion:.3g}" for k, p in enumerate(front.poses, 1)])

    def _setting_edited(self, name: str):
        def on_update(event):
            if event.client is not None:  # edited in the page, not set by the server from the state
                value = self.settings[name].value
                kind = type(getattr(self.app.state.settings, name))
                self.app.change_setting(name, kind(value) if kind in (int, float) else value)
        return on_update

    def _add_files_folder(self) -> None:
        g, app, name = self.gui, self.app, self.rig.name
        state = app.state
        with self._folder("Files", expand_by_default=False):
            dl_stl, dl_3mf = g.add_button("Download STL"), g.add_button("Download 3MF")
            dl_pose = g.add_button("Download pose JSON", hint="The pose, its print rotation and the locked bones")
            upload = g.add_upload_button("Upload pose…", mime_type="application/json")
            g.add_markdown(f"On the server, in {state.workdir.resolve()} only:")
            pose_path = g.add_text("Pose file", f"{name}-pose.json", hint=f"Relative to {state.workdir.resolve()}")
            save, load = g.add_button("Save pose on the server"), g.add_button("Load pose from the server")
            mesh_path = g.add_text("Mesh file", f"{name}-posed.stl",
                                   hint="Relative to the folder above; .stl .3mf .obj .ply; as printed, on the plate")
            export = g.add_button("Export mesh on the server")
        save.on_click(lambda _e: app.save_pose(pose_path.value))
        load.on_click(lambda _e: app.load_pose(pose_path.value))
        export.on_click(lambda _e: app.export_mesh(mesh_path.value))
        upload.on_upload(lambda _e: app.load_pose_bytes(upload.value.name, upload.value.content))
        # a download goes to the browser that asked, no other
        dl_pose.on_click(lambda e: app.download(f"{name}-pose.json", state.pose_bytes, e.client))
        dl_stl.on_click(lambda e: app.download(f"{name}-posed.stl", lambda: state.mesh_bytes("stl"), e.client))
        dl_3mf.on_click(lambda e: app.download(f"{name}-posed.3mf", lambda: state.mesh_bytes("3mf"), e.client))

    # ------------------------------------------------------------------ show
    def show_status(self, text: str, error: bool = False) -> None:
        """The status line (an error stands out)."""
        self.status.content = f"**⚠ Error:** {text}" if error else f"**Status:** {text}"

    def show_view(self, frame: str) -> None:
        """Show which frame the model is drawn in (``standing`` or ``print``)."""
        label = next(k for k, v in VIEWS.items() if v == frame)
        if self.view.value != label:
            self.view.value = label

    def show_measures(self, markdown: str) -> None:
        """The energies list (see :func:`measures_markdown`)."""
        self.measures.content = markdown

    def select(self, bone: int, degrees: np.ndarray) -> None:
        """Show the selected bone in the dropdown and its angles on the sliders.

        Parameters
        ----------
        bone : int
            0-based.
        degrees : (3,) float64
            The bone's Euler angles, degrees (rounded to 0.1°).
        """
        if self.bone.value != self.names[bone]:
            self.bone.value = self.names[bone]
        for sl, v in zip(self.sliders, degrees):
            v = float(np.clip(np.round(v, 1), -180.0, 180.0))
            if abs(sl.value - v) > 1e-9:
                sl.value = v

    def show_bone(self, bone: int, fixed: np.ndarray, locked: np.ndarray | None = None) -> None:
        """Describe the selected bone (0-based); ``fixed`` (m,) bool: bones the search keeps; ``locked`` (m,)
        bool: those the user locked (the checkbox follows)."""
        rig = self.rig
        kids = int(np.sum(rig.parents == bone))
        parent = "none" if rig.parents[bone] < 0 else rig.parents[bone] + 1
        is_locked = locked is not None and bool(locked[bone])
        how = "locked: kept as it is" if is_locked else "fixed" if fixed[bone] else "free"
        self.bone_info.content = (f"Bone {bone + 1}: joints {rig.bones[bone, 0] + 1}→{rig.bones[bone, 1] + 1}, "
                                  f"parent {parent}, {kids} child bone(s); {how} in the search.")
        if self.lock.value != is_locked:
            self.lock.value = is_locked

    def show_settings(self, settings: SearchSettings, fixed: np.ndarray) -> None:
        """Show the search settings in force: the widgets, the fixed bones, the search's threshold.

        A widget whose value the state refused (see :attr:`invalid`) keeps it,
        with the reason below.
        """
        for name, h in self.settings.items():
            value = getattr(settings, name)
            if name in self.invalid:
                continue
            if isinstance(value, tuple):  # a bone list: keep the text as typed when it means the same
                if settings.replace(**{name: h.value}) != settings:
                    h.value = ",".join(value)
            else:
                h.value = value
        fixed_list = ", ".join(str(b + 1) for b in np.flatnonzero(fixed)) or "none"
        notes = "".join(f"\n\n⚠ {message}" for message in self.invalid.values())
        orient = (", and turns the model to print it with less (Orientation: free)" if settings.orient == "free"
                  else "; the model is printed as it stands (Orientation: keep)")
        self.fixed_info.content = (f"Fixed in the search (grey): bones {fixed_list}. Default: the bones on the "
                                   "plate and the bones joining them; the rest of the body turns about "
                                   f"them. The search counts faces past "
                                   f"{settings.search_overhang_angle:.3g}° (threshold + margin) as needing "
                                   f"support{orient}.{notes}")

    def search_started(self, total: int) -> None:
        """Disable Optimize, enable Cancel, empty the progress bar."""
        self.optimize.disabled = True
        self.cancel.disabled = False
        self.progress.value = 0.0
        self.search_info.content = f"iteration 0 / {total}"

    def show_progress(self, progress: dict) -> None:
        """Progress bar and best objective of the running search."""
        it, total, value = progress["iteration"], progress["iterations"], progress["value"]
        if progress.get("phase"):  # after the search: PrusaSlicer chooses among its answers
            self.show_status(f"{progress['phase']} with PrusaSlicer ...")
            return
        self.progress.value = 100.0 * it / max(total, 1)
        self.search_info.content = f"iteration {it} / {total} · best objective {_fmt(value)}"
        self.show_status(f"searching, iteration {it} / {total}, best objective {_fmt(value)}")

    def search_finished(self) -> None:
        """Enable Optimize again."""
        self.optimize.disabled = False
        self.cancel.disabled = True
        self.progress.value = 100.0
