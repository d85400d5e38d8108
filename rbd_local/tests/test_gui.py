"""The operator GUI under a private Xvfb, wired to the real RobotLink and a fake bridge."""

import io
import os
import shutil
import subprocess

import pytest
from rbd_testkit import stays_unchanged
from xvfb import pump, pump_for

from rbd_local.link import EM_STOP_SERVICE, PATH_QUEUE_TOPIC, STATE_TOPIC, STATUS_TOPIC, RobotLink

pytestmark = pytest.mark.skipif(shutil.which("Xvfb") is None, reason="Xvfb not installed")

DOCS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs")


@pytest.fixture(scope="module")
def app(display):
    import customtkinter as ctk
    from fake_bridge import FakeBridge

    from rbd_local.gui.app import OperatorGui

    bridge = FakeBridge().start()
    root = ctk.CTk()
    holder = {}
    link = RobotLink(
        "127.0.0.1", bridge.port, retry_s=0.2, connect_timeout_s=3.0,
        on_status=lambda s: holder["gui"].post_status(s), on_state=lambda s: holder["gui"].post_state(s),
        on_path_queue=lambda n: holder["gui"].post_path_queue(n),
        on_connection=lambda up: holder["gui"].post_connection(up),
    )
    gui = holder["gui"] = OperatorGui(root, link, em_stop_timeout=5.0)
    link.start()
    state = {"root": root, "gui": gui, "link": link, "bridge": bridge}
    pump(root, lambda: link.connected)
    assert bridge.wait_for(lambda: {STATUS_TOPIC, PATH_QUEUE_TOPIC, STATE_TOPIC} <= set(bridge.subscribed))
    yield state
    link.stop()
    state["bridge"].stop()
    root.destroy()


def screen_pixel(widget):
    """Colour actually rendered at the centre of ``widget`` (X server screenshot)."""
    from PIL import Image

    widget.update()
    x = widget.winfo_rootx() + widget.winfo_width() // 2
    y = widget.winfo_rooty() + 8
    png = subprocess.run(["import", "-window", "root", "png:-"], stdout=subprocess.PIPE, check=True, timeout=30).stdout
    return Image.open(io.BytesIO(png)).convert("RGB").getpixel((x, y))


def em_stops(bridge):
    """The e-stop calls the bridge received (the Teach panel also reads the tricks through rosapi)."""
    with bridge._lock:
        return [c for c in bridge.service_calls if c[0] == EM_STOP_SERVICE]


def hex_rgb(colour):
    return tuple(int(colour[i : i + 2], 16) for i in (1, 3, 5))


def test_connection_indicator_shows_connected(app):
    # "CONNECTED" is also a substring of "DISCONNECTED": wait for the connected text itself.
    assert pump(app["root"], lambda: app["gui"].connection_label.cget("text").startswith("● CONNECTED"))
    assert app["gui"].connection_label.cget("fg_color") == "#2e7d32"


@pytest.mark.parametrize(
    "status, colour",
    [("idle", "#1565c0"), ("running", "#2e7d32"), ("collision", "#ef6c00"), ("emergency", "#c62828")],
)
def test_state_colour_follows_published_status(app, status, colour):
    app["bridge"].push(STATUS_TOPIC, {"data": status})
    assert pump(app["root"], lambda: app["gui"].state_colour() == colour)
    assert app["gui"].state_label.cget("text") == status.upper()
    rendered = screen_pixel(app["gui"].state_label)
    assert all(abs(a - b) <= 12 for a, b in zip(rendered, hex_rgb(colour))), (rendered, colour)


@pytest.mark.parametrize(
    "state, colour",
    [("BLOCKED", "#6a1b9a"), ("ESCAPING", "#00838f"), ("AVOIDING", "#00838f"), ("DODGING", "#00838f")],
)
def test_avoidance_states_have_their_own_label_and_colour_but_the_estop_wins(app, state, colour):
    app["bridge"].push(STATUS_TOPIC, {"data": "running"})
    app["bridge"].push(STATE_TOPIC, {"data": state})
    assert pump(app["root"], lambda: app["gui"].state_colour() == colour)
    assert app["gui"].state_label.cget("text") == state
    rendered = screen_pixel(app["gui"].state_label)
    assert all(abs(a - b) <= 12 for a, b in zip(rendered, hex_rgb(colour))), (rendered, colour)
    app["bridge"].push(STATUS_TOPIC, {"data": "emergency"})
    assert pump(app["root"], lambda: app["gui"].state_colour() == "#c62828")
    app["bridge"].push(STATE_TOPIC, {"data": "WAITING_FOR_GESTURE"})
    app["bridge"].push(STATUS_TOPIC, {"data": "idle"})
    assert pump(app["root"], lambda: app["gui"].state_colour() == "#1565c0")


def test_unknown_status_is_grey_not_a_crash(app):
    app["bridge"].push(STATUS_TOPIC, {"data": "bogus"})
    assert pump(app["root"], lambda: app["gui"].state_colour() == "#616161")


def test_estop_click_calls_the_service(app):
    bridge, gui, root = app["bridge"], app["gui"], app["root"]
    n = len(em_stops(bridge))
    b = gui.estop_button
    root.update()
    x = b.winfo_rootx() + b.winfo_width() // 2
    y = b.winfo_rooty() + b.winfo_height() // 2
    subprocess.run(["xdotool", "mousemove", str(x), str(y), "click", "1"], check=True, timeout=10)
    assert pump(root, lambda: len(em_stops(bridge)) > n)
    assert em_stops(bridge)[n] == (EM_STOP_SERVICE, {"data": True})
    assert pump(root, lambda: gui.message_label.cget("text") == "E-STOP ENGAGED")


def test_release_needs_a_second_deliberate_click(app):
    bridge, gui, root = app["bridge"], app["gui"], app["root"]
    n = len(em_stops(bridge))
    gui.release_button.invoke()

    def calls():
        root.update()
        return len(em_stops(bridge))

    # the click was taken (the button asks for confirmation), and no call reaches the bridge
    stays_unchanged(calls, lambda: "Confirm" in gui.release_button.cget("text"), hold=0.6,
                    what="one click must not release the e-stop: the bridge's e-stop calls", proof="the release armed")
    assert len(em_stops(bridge)) == n, "one click must not release the e-stop"
    gui.release_button.invoke()
    assert pump(root, lambda: len(em_stops(bridge)) > n)
    assert em_stops(bridge)[n] == (EM_STOP_SERVICE, {"data": False})
    assert pump(root, lambda: gui.message_label.cget("text") == "e-stop released")


def test_next_five_moves_update_and_dequeue(app):
    bridge, gui, root = app["bridge"], app["gui"], app["root"]
    names = ["walk: to (0.6, 0)", "walk: turn to face back", "walk: to (-0.6, 0)", "walk: face forward",
             "walk: to start", "spin: yaw pi", "spin: yaw 0"]
    bridge.push(PATH_QUEUE_TOPIC, {"command": "walk", "names": names})
    assert pump(root, lambda: gui.shown_moves()[0] == "1. " + names[0])
    assert gui.shown_moves() == ["%d. %s" % (i + 1, n) for i, n in enumerate(names[:5])]
    bridge.push(PATH_QUEUE_TOPIC, {"command": "walk", "names": names[1:]})  # first move reached
    assert pump(root, lambda: gui.shown_moves()[0] == "1. " + names[1])
    assert gui.shown_moves()[4] == "5. " + names[5]
    bridge.push(PATH_QUEUE_TOPIC, {"command": "walk", "names": names[5:]})
    assert pump(root, lambda: gui.shown_moves()[:3] == ["1. " + names[5], "2. " + names[6], ""])


def test_window_screenshot(app):
    from rbd_local.gui.screenshot import save_window

    bridge, gui, root = app["bridge"], app["gui"], app["root"]
    bridge.push(STATUS_TOPIC, {"data": "running"})
    bridge.push(STATE_TOPIC, {"data": "EXECUTING"})
    bridge.push(PATH_QUEUE_TOPIC, {"command": "walk", "names": [
        "walk: to (0.6, 0)", "walk: turn to face back", "walk: to (-0.6, 0)", "walk: face forward", "walk: to start"]})
    gui.post_gesture("swipe_right", "walk", 0.93)
    assert pump(root, lambda: gui.state_colour() == "#2e7d32" and gui.shown_moves()[4].startswith("5."))
    assert gui.gesture_label.cget("text") == "last gesture: swipe_right → walk (93 %)"
    pump_for(root, 0.3)
    # The README's screenshot (docs/gui.png, with teach mode) is made by test_gui_teach.py.
    cache = os.path.join(os.path.dirname(DOCS), ".cache")
    os.makedirs(cache, exist_ok=True)
    path = os.path.join(cache, "gui.png")
    save_window(root, path)
    from PIL import Image

    assert Image.open(path).size[0] >= 1000  # the three columns: controls, moves, teach panel
    # without a gesture source in this window the Teach panel says how to get one
    assert not gui.teach_panel.desk and "no camera" in gui.teach_panel.message_label.cget("text")


def test_disconnected_is_obvious_and_estop_says_it_could_not(app):
    bridge, gui, root = app["bridge"], app["gui"], app["root"]
    bridge.stop()
    assert pump(root, lambda: "DISCONNECTED" in gui.connection_label.cget("text"))
    assert gui.connection_label.cget("fg_color") == "#c62828"
    gui.estop_button.invoke()
    assert pump(root, lambda: gui.message_label.cget("text").startswith("E-STOP FAILED"))
    assert "NOT delivered" in gui.message_label.cget("text")
    # the bridge comes back: the indicator recovers and the e-stop works again
    from fake_bridge import FakeBridge

    app["bridge"] = FakeBridge(port=bridge.port).start()
    assert pump(root, lambda: "CONNECTED ws" in gui.connection_label.cget("text"))
    gui.estop_button.invoke()
    assert pump(root, lambda: gui.message_label.cget("text") == "E-STOP ENGAGED")
    assert em_stops(app["bridge"]) == [(EM_STOP_SERVICE, {"data": True})]


def test_rbd_gui_entry_point_with_in_process_gesture_recognition(display, tmp_path, hand_photos):
    import sys

    import cv2
    from fake_bridge import FakeBridge

    from rbd_local.gestures.photo_clip import moving_photo_frames, write_clip

    clip = str(tmp_path / "right.avi")
    frames = moving_photo_frames(cv2.imread(hand_photos["handSrc.jpg"]), "right", distance=0.4, hold_s=1.0)
    write_clip(frames, clip)
    bridge = FakeBridge().start()
    try:
        shot = tmp_path / "shot.png"
        env = dict(os.environ, DISPLAY=display,
                   PYTHONPATH=os.path.join(os.path.dirname(DOCS), "src"))
        proc = subprocess.run([sys.executable, "-m", "rbd_local.gui_app", "--port", str(bridge.port), "--video", clip,
                               "--screenshot", str(shot), "--screenshot-delay", "8"],
                              env=env, capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr[-2000:]
        assert shot.stat().st_size > 1000
        assert bridge.wait_for(lambda: STATUS_TOPIC in bridge.subscribed)
        assert bridge.published_on("/rbd_local/heartbeat"), "the GUI app sends the operator heartbeat"
        assert bridge.published_on("/rbd_gestrec/gesture") == [{"data": "walk"}]
    finally:
        bridge.stop()
