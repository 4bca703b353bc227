"""The browser app is a door: only the page the tool printed connects, files stay in one folder, values are checked.

The attacker here is a plain HTTP or websocket client, as one would write it:
another origin, no token, a wrong Host header, paths that leave the folder,
values the widgets would never send.
"""

import http.client
import os
from urllib.parse import urlsplit

import numpy as np
import pytest
import viser
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from supportless.apps.ui.guard import Guard, is_loopback
from supportless.apps.ui.state import EditorState
from supportless.base.errors import InputError

PROTOCOL = f"viser-v{viser.__version__}"


@pytest.fixture(scope="module")
def app(branch_app):
    return branch_app


def get(app, path="/", headers=None):
    conn = http.client.HTTPConnection("127.0.0.1", app.port, timeout=10)
    conn.request("GET", path, headers=headers or {})
    r = conn.getresponse()
    return r.status, dict(r.getheaders()), r.read()


def ws(app, *, origin=None, cookie=None, host=None, query=""):
    headers = {}
    if cookie is not None:
        headers["Cookie"] = cookie
    if host is not None:
        headers["Host"] = host
    return connect(f"ws://127.0.0.1:{app.port}/{query}", origin=origin, additional_headers=headers,
                   subprotocols=[PROTOCOL], open_timeout=10)


def cookie_of(app) -> str:
    status, headers, _ = get(app, f"/?token={app.guard.token}")
    assert status == 200
    set_cookie = headers["Set-Cookie"]
    assert "HttpOnly" in set_cookie and "SameSite=Strict" in set_cookie
    return set_cookie.split(";")[0]


def test_the_page_needs_its_token(app):
    status, _, body = get(app)
    assert status == 403 and b"token" in body and b"<html" not in body.lower()
    status, _, _ = get(app, "/?token=wrong")
    assert status == 403
    status, _, body = get(app, f"/?token={app.guard.token}")
    assert status == 200 and b"<html" in body.lower()
    status, _, _ = get(app, "/", {"Cookie": cookie_of(app)})  # the page's later requests carry the cookie
    assert status == 200


def test_a_foreign_host_header_is_refused(app):
    status, _, _ = get(app, f"/?token={app.guard.token}", {"Host": f"evil.example:{app.port}"})
    assert status == 403
    status, _, _ = get(app, f"/?token={app.guard.token}", {"Host": f"localhost:{app.port}"})
    assert status == 200


def test_only_the_printed_page_gets_the_websocket_and_the_scene(app):
    own = f"http://127.0.0.1:{app.port}"
    cookie = cookie_of(app)
    for kwargs in ({"origin": "http://evil.example", "cookie": cookie},  # a page of another site
                   {"origin": own},  # no token
                   {"origin": own, "cookie": "supportless-token-1=" + app.guard.token},  # another port's cookie
                   {"origin": None, "cookie": cookie},  # no Origin: not a browser page of ours
                   {"origin": f"http://evil.example:{app.port}", "cookie": cookie, "host": f"evil.example:{app.port}"}):
        with pytest.raises(InvalidStatus) as info:
            ws(app, **kwargs)
        assert info.value.response.status_code == 403, kwargs
    with ws(app, origin=own, cookie=cookie) as socket:  # the page itself
        assert len(socket.recv(timeout=10)) > 0  # the scene arrives
    with ws(app, origin=own, query=f"?token={app.guard.token}") as socket:
        assert len(socket.recv(timeout=10)) > 0


def test_guard_unit_checks():
    g = Guard("127.0.0.1", token="t" * 43)
    g.port = 9000

    class Request:
        def __init__(self, path, **headers):
            self.path, self.headers = path, {k.replace("_", "-"): v for k, v in headers.items()}

    assert g.refusal(Request("/?token=" + "t" * 43, Host="127.0.0.1:9000")) is None
    assert "token" in g.refusal(Request("/?token=" + "t" * 42, Host="127.0.0.1:9000"))
    assert "Host" in g.refusal(Request("/?token=" + "t" * 43, Host="attacker.example:9000"))
    assert g.refusal(Request("/", Host="[::1]:9000", Cookie=f"supportless-token-9000={'t' * 43}")) is None
    assert "origin" in g.refusal(Request("/", Host="127.0.0.1:9000", Upgrade="websocket",
                                         Origin="http://127.0.0.1:9001", Cookie=f"supportless-token-9000={'t' * 43}"))
    network = Guard("0.0.0.0", token="x")
    network.port = 1
    assert network.refusal(Request("/?token=x", Host="192.0.2.7:1")) is None  # any name; the token decides
    assert network.refusal(Request("/", Host="192.0.2.7:1")) is not None
    assert is_loopback("127.0.0.2") and is_loopback("[::1]") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.2")
    assert len(Guard("127.0.0.1").token) >= 40 and Guard("x").token != Guard("x").token


# --------------------------------------------------------------------------- files


@pytest.fixture()
def folder_state(branch_rig, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    (tmp_path / "work-sibling").mkdir()
    os.symlink(tmp_path, work / "link-out")
    (tmp_path / "secret.json").write_text("{}")
    return EditorState(branch_rig, workdir=work), tmp_path


@pytest.mark.parametrize("name", ["{out}/escaped.json", "../escaped.json", "sub/../../escaped.json", "~/escaped.json",
                                  "../work-sibling/escaped.json", "link-out/escaped.json", "/etc/passwd", ""])
def test_paths_that_leave_the_folder_are_refused_for_save_export_and_load(folder_state, name):
    state, outside = folder_state
    before = sorted(p.relative_to(outside) for p in outside.rglob("*"))
    path = name.format(out=outside)
    for action in (state.save_pose, state.export_mesh, state.load_pose):
        with pytest.raises(InputError, match="only inside") as info:
            action(path.replace(".json", ".stl") if action == state.export_mesh else path)
        assert "no such file" not in str(info.value)
    assert sorted(p.relative_to(outside) for p in outside.rglob("*")) == before  # nothing created anywhere


def test_a_refused_read_says_the_same_whether_or_not_the_file_exists(folder_state):
    state, outside = folder_state
    messages = []
    for name in ("../secret.json", "../no-such.json"):
        with pytest.raises(InputError) as info:
            state.load_pose(name)
        messages.append(str(info.value).replace("secret", "X").replace("no-such", "X"))
    assert messages[0] == messages[1]


def test_inside_the_folder_files_are_written_and_never_overwritten(folder_state):
    state, _ = folder_state
    first = state.save_pose("pose.json")
    second = state.save_pose("pose.json")
    assert first.name == "pose.json" and second.name == "pose-1.json"
    assert first.parent == second.parent == state.workdir.resolve()
    mesh = state.export_mesh("posed.stl")
    assert mesh.is_file() and state.export_mesh("posed.stl").name == "posed-1.stl"
    assert state.load_pose("pose.json") == first
    with pytest.raises(InputError, match="does not exist"):
        state.save_pose("missing-folder/pose.json")
    assert not (state.workdir / "missing-folder").exists()


def test_the_page_writes_inside_its_folder_and_says_the_full_path(app):
    assert app.save_pose("from-page.json")
    assert str(app.state.workdir.resolve() / "from-page.json") in app.status
    assert not app.save_pose("../outside.json")
    assert "only inside" in app.status
    assert not (app.state.workdir.parent / "outside.json").exists()


# --------------------------------------------------------------------------- values


@pytest.mark.parametrize("name, value", [("particles", 99_999_999), ("particles", 0), ("iterations", -1),
                                         ("iterations", 10 ** 9), ("w_arap", float("nan")), ("w_prior", -1.0),
                                         ("joint_limit", 500.0), ("fix", "99")])
def test_out_of_range_settings_from_a_client_are_refused(app, name, value):
    before = app.state.settings
    assert not app.change_setting(name, value)
    assert app.state.settings == before
    assert name in app.panel.invalid


def test_the_cli_refuses_the_same_ranges(tmp_path):
    from click.testing import CliRunner

    from supportless.apps.cli import main
    from supportless.apps.ui.panel import NUMBER_SETTINGS
    from supportless.search.settings import RANGES

    out = CliRunner().invoke(main, ["optimize", "demo:branch", "--particles", "99999999", "-o", str(tmp_path / "x.stl")])
    low, high = RANGES["particles"]
    assert out.exit_code == 2 and f"{low}<=x<={high}" in out.stderr  # the settings' own range
    fields = {name: limits for name, _, limits in NUMBER_SETTINGS}
    assert (fields["particles"]["min"], fields["particles"]["max"]) == (low, high)  # and the app's
    assert (fields["iterations"]["min"], fields["overhang_angle"]["max"]) == (RANGES["iterations"][0], 90.0)


def test_a_network_host_is_said_as_such(branch_rig, tmp_path, capfd):
    from supportless.apps.ui.app import run_app

    a = run_app(branch_rig, host="0.0.0.0", block=False, workdir=tmp_path)
    try:
        err = capfd.readouterr().err
        assert "warning" in err and "0.0.0.0" in err and "token" in err
        assert urlsplit(a.url).query.startswith("token=")
        status, _, _ = get(a)  # reachable from the network, but never without the token
        assert status == 403
    finally:
        a.stop()
    a = run_app(branch_rig, host="127.0.0.1", block=False, workdir=tmp_path)
    try:
        assert "warning" not in capfd.readouterr().err
    finally:
        a.stop()


def test_downloads_go_to_the_browser_that_asked(app):
    sent = []

    class Client:
        def send_file_download(self, name, data, save_immediately=True):
            sent.append((self, name, len(data)))

    asker = Client()
    app.download("pose.json", app.state.pose_bytes, asker)
    assert [(c, n) for c, n, _ in sent] == [(asker, "pose.json")]
    assert np.all([size > 0 for *_, size in sent])


def test_bone_edits_from_a_client_are_checked(branch_rig, tmp_path):
    state = EditorState(branch_rig, workdir=tmp_path)
    before = state.get_angles()
    for bad in (99, -1, 1.5, True, "0"):
        with pytest.raises(ValueError, match="not one of"):
            state.set_bone_angles(bad, [0.0, 0.0, 10.0])
        with pytest.raises(ValueError, match="not one of"):
            state.select_bone(bad)
    with pytest.raises(ValueError, match="finite"):
        state.set_bone_angles(0, [float("nan"), 0.0, 0.0])
    with pytest.raises(ValueError, match="finite"):
        state.set_bone_rotation(0, np.full((3, 3), np.inf))
    np.testing.assert_array_equal(state.get_angles(), before)


def test_a_client_changes_values_only_and_no_disabled_button_fires(app):
    import asyncio

    from viser import _messages

    from supportless.apps.ui.guard import value_updates

    interface = app.server._websock_server
    handlers = interface._incoming_handlers[_messages.GuiUpdateMessage]
    assert app.server.gui._handle_gui_updates not in handlers  # viser's own handler is behind the filter
    loop = interface._background_event_loop
    particles = app.panel.settings["particles"]
    # viser's own handler sets any field of the widget's state a client names: "removed" unhooks the widget
    # (checked by hand: it does, without the filter)
    message = _messages.GuiUpdateMessage(particles._impl.uuid, {"removed": True, "update_timestamp": 5.0})
    for handler in handlers:
        asyncio.run_coroutine_threadsafe(handler(0, message), loop).result(10)
    assert not particles._impl.removed and particles._impl.update_timestamp != 5.0
    assert value_updates(particles, {"value": 12, "max": 1}) == {"value": 12}
    button = app.panel.optimize
    assert value_updates(button, {"value": True}) == {"value": True}
    button.disabled = True
    try:
        assert value_updates(button, {"value": True}) == {}  # a disabled button does not fire
    finally:
        button.disabled = False
