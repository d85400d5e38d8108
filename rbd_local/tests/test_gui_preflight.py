"""The operator window's Preflight panel under the session's Xvfb, with the real RobotLink and a fake bridge.

The fake bridge plays the robot's preflight_server: it answers ``/preflight/run`` with a report
whose LiDAR check fails (built from rbd_msgs' definitions in ``preflight_reports``) and pushes
reports on the latched ``/preflight/report`` when the window subscribes.
"""

import io
import os
import shutil
import subprocess

import preflight_reports as pr
import pytest
from xvfb import pump, pump_for

from rbd_local.link import PREFLIGHT_SERVICE, PREFLIGHT_TOPIC, RobotLink

pytestmark = pytest.mark.skipif(shutil.which("Xvfb") is None, reason="Xvfb not installed")

PKG_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RED = "#c62828"
GREEN = "#2e7d32"
GREY = "#757575"


@pytest.fixture
def window(display):
    import customtkinter as ctk
    from fake_bridge import FakeBridge

    from rbd_local.gui.app import OperatorGui

    bridge = FakeBridge()

    def robot(service, args):
        if service == PREFLIGHT_SERVICE:
            return True, {"report": pr.report(secs=1764084662)}
        return True, {"success": True, "message": "ok"}

    bridge.service_handler = robot
    bridge.start()
    root = ctk.CTk()
    holder = {}
    link = RobotLink("127.0.0.1", bridge.port, retry_s=0.2, connect_timeout_s=3.0,
                     on_connection=lambda up: holder["gui"].post_connection(up),
                     on_preflight=lambda r: holder["gui"].post_preflight(r))
    gui = holder["gui"] = OperatorGui(root, link)
    state = {"root": root, "gui": gui, "panel": gui.preflight_panel, "bridge": bridge, "link": link}
    yield state
    link.stop()
    state["bridge"].stop()
    root.destroy()


def click(widget):
    """A real mouse click (xdotool) in the middle of ``widget``."""
    widget.update()
    x = widget.winfo_rootx() + widget.winfo_width() // 2
    y = widget.winfo_rooty() + widget.winfo_height() // 2
    subprocess.run(["xdotool", "mousemove", str(x), str(y), "click", "1"], check=True, timeout=10)


def screen_pixel(widget):
    """Colour the X server actually shows near the middle of ``widget``'s left edge."""
    from PIL import Image

    widget.update()
    x = widget.winfo_rootx() + 4
    y = widget.winfo_rooty() + widget.winfo_height() // 2
    png = subprocess.run(["import", "-window", "root", "png:-"], stdout=subprocess.PIPE, check=True, timeout=30).stdout
    return Image.open(io.BytesIO(png)).convert("RGB").getpixel((x, y))


def hex_rgb(colour):
    return tuple(int(colour[i : i + 2], 16) for i in (1, 3, 5))


def test_preflight_panel_latched_report_run_click_and_link_loss(window):
    root, gui, panel, bridge, link = window["root"], window["gui"], window["panel"], window["bridge"], window["link"]
    # before the link is up the panel says so and Run is off
    assert "not connected" in panel.message_label.cget("text")
    assert panel.run_button.cget("state") == "disabled" and panel.summary() == "no report yet"
    gui.tabs.set("Preflight")
    link.start()
    assert pump(root, lambda: link.connected and panel.run_button.cget("state") == "normal")
    assert "not connected" not in panel.message_label.cget("text")

    # the robot's last report (latched) is shown on connect: all PASS, READY
    assert bridge.wait_for(lambda: PREFLIGHT_TOPIC in bridge.subscribed)
    bridge.push(PREFLIGHT_TOPIC, pr.all_pass())
    assert pump(root, lambda: panel.summary() == "READY")
    assert panel.ready_label.cget("fg_color") == GREEN
    assert [r[0] for r in panel.row_texts()] == ["PASS", "PASS"]
    assert panel.message_label.cget("text") == ""
    assert panel.row_colour(0) == GREEN

    # a real click on Run: the robot's answer has one FAIL, shown red with what to do
    click(panel.run_button)
    assert pump(root, lambda: panel.summary().startswith("NOT READY")), panel.message_label.cget("text")
    with bridge._lock:
        runs = [c for c in bridge.service_calls if c[0] == PREFLIGHT_SERVICE]
    assert runs == [(PREFLIGHT_SERVICE, {"duration": 0.0})]
    assert panel.summary() == "NOT READY (1 FAIL)"
    assert panel.ready_label.cget("fg_color") == RED
    rows = panel.row_texts()
    assert rows == [
        ("PASS", "A1 HighState", "500.0 Hz (LCM tap 499.8 Hz)", ""),
        ("FAIL", "LiDAR /ouster/points", "no message in 3.0 s",
         "→ is ouster-ros running and the sensor powered? check the LiDAR's Ethernet link"),
        ("SKIP", "LiDAR cloud layout", "needs LiDAR /ouster/points", ""),
    ]
    assert [panel.row_colour(i) for i in range(3)] == [GREEN, RED, GREY]
    from rbd_local.gui.preflight_panel import report_time

    assert panel.time_label.cget("text") == "report of %s, 3.0 s observed" % report_time(1764084662.25)
    pump_for(root, 0.3)
    # what the X server shows: the FAIL badge and the NOT READY line are red
    for widget in (panel.rows[1][0], panel.ready_label):
        shown = screen_pixel(widget)
        assert max(abs(a - b) for a, b in zip(shown, hex_rgb(RED))) < 30, shown
    save_screenshot(root)

    # the link goes down: the panel says so, keeps the last report and Run is off
    bridge.stop()
    assert pump(root, lambda: "not connected" in panel.message_label.cget("text"))
    assert "last report" in panel.message_label.cget("text")
    assert panel.run_button.cget("state") == "disabled"
    assert panel.summary() == "NOT READY (1 FAIL)"


def test_a_failed_run_says_why_and_keeps_the_window_alive(window):
    root, gui, panel, bridge, link = window["root"], window["gui"], window["panel"], window["bridge"], window["link"]
    bridge.service_handler = lambda service, args: (False, "service %s does not exist" % service)
    gui.tabs.set("Preflight")
    link.start()
    assert pump(root, lambda: panel.run_button.cget("state") == "normal")
    panel.run_button.invoke()
    assert pump(root, lambda: panel.message_label.cget("text").startswith("preflight failed"))
    assert "does not exist" in panel.message_label.cget("text")
    assert panel.run_button.cget("state") == "normal" and panel.summary() == "no report yet"


def save_screenshot(root):
    """``.cache/gui_preflight.png``; ``docs/preflight.png`` (the README's) when missing or RBD_UPDATE_DOCS=1."""
    from rbd_local.gui.screenshot import save_window

    cache = os.path.join(PKG_ROOT, ".cache")
    os.makedirs(cache, exist_ok=True)
    path = os.path.join(cache, "gui_preflight.png")
    save_window(root, path)
    docs_png = os.path.join(PKG_ROOT, "docs", "preflight.png")
    if os.environ.get("RBD_UPDATE_DOCS") == "1" or not os.path.exists(docs_png):
        shutil.copyfile(path, docs_png)
