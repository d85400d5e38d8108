"""System test: ``sim.launch gui:=true`` under a private Xvfb, and the GUI's next five moves for the new tricks.

1. ``roslaunch rbd_bringup sim.launch gui:=true gesture_video:=CLIP`` on a private master with
   DISPLAY on a private Xvfb: the operator window opens (found by its title on that display and
   grabbed), its heartbeat reaches ROS, and the gesture it recognises in the clip (the real hand
   of an opencv-doc photo moved right) reaches rbd_gestrec.
2. On the same stack an operator window in this process (rbd_local's ``OperatorGui`` with the
   real ``RobotLink``) releases the e-stop and each taught-gesture trick (bow, look_around, sit,
   shake) is sent as the laptop sends a taught gesture; the window's "next moves" must show the
   trick's first five step names as rbd_navigation's ``config/tricks.yaml`` defines them (read
   here with yaml, not through any RoboDog code), then the trick must finish.

Run it under the shared lock (it starts a simulated stack):
``flock /tmp/rbd-sim.lock python3 -m pytest -q tests/test_sim_gui.py``.
"""

import os
import shutil
import subprocess
import sys

import pytest
import yaml

from rbd_testkit import RosEnv, free_port, wait_for, wait_for_port

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LOCAL = os.path.join(ROOT, "rbd_local")
NEW_TRICKS = ("bow", "look_around", "sit", "shake")

pytestmark = pytest.mark.skipif(shutil.which("Xvfb") is None or shutil.which("xdotool") is None,
                                reason="Xvfb and xdotool are needed")


def _pumped(root, pred):
    """``pred`` checked after the Tk events of ``root`` were handled (for ``wait_for``)."""
    return lambda: root.update() or pred()


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    sys.path.insert(0, os.path.join(LOCAL, "src"))
    sys.path.insert(0, os.path.join(LOCAL, "tests"))
    import cv2
    from xvfb import Xvfb

    from rbd_local.gestures.photo_clip import moving_photo_frames, write_clip
    from rbd_local.testdata import fetch_hand_photos

    out = tmp_path_factory.mktemp("sim_gui")
    photo = fetch_hand_photos(os.path.join(LOCAL, ".cache", "hand_photos"))["handSrc.jpg"]
    clip = str(out / "swipe_right.avi")
    write_clip(moving_photo_frames(cv2.imread(photo), "right", distance=0.4, hold_s=1.0), clip)
    x = Xvfb("1280x800x24").start()
    ros = RosEnv()
    ros.env["DISPLAY"] = x.display
    ros.env["PYTHONPATH"] = os.path.join(LOCAL, "src") + os.pathsep + ros.env.get("PYTHONPATH", "")
    ros.env["XDG_DATA_HOME"] = str(out / "xdg")  # never the user's taught gestures
    ros.env["XDG_RUNTIME_DIR"] = str(out)
    port = free_port()
    launch = ros.launch("rbd_bringup", "sim.launch", "gui:=true", "gesture_video:=" + clip,
                        "bridge_port:=%d" % port, "lidar_columns:=512", "localization:=false", name="roslaunch")
    old_display = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = x.display
    ros.use_in_this_process()
    try:
        wait_for_port(port, timeout=120, proc=launch)
        yield {"ros": ros, "port": port, "display": x.display, "launch": launch, "out": out}
    finally:
        if old_display is None:
            os.environ.pop("DISPLAY", None)
        else:
            os.environ["DISPLAY"] = old_display
        ros.close()
        x.stop()


@pytest.fixture(scope="module")
def video_gesture(stack):
    """The gesture the stack's operator GUI recognised in its video, taken from rbd_gestrec.

    The robot is still in its power-up e-stop, so the controller does not take it; taking it
    here, before any test releases the e-stop, keeps it from being performed later (the tests
    of this module then start from the same state in any order)."""
    import rospy

    from rbd_msgs.srv import GetLastGesture

    rospy.wait_for_service("/rbd_gestrec/get_last_gesture", timeout=120)
    last = rospy.ServiceProxy("/rbd_gestrec/get_last_gesture", GetLastGesture)
    got = []
    wait_for(lambda: got.append(last().command) or got[-1] == "walk", 120, 0.3)
    return got[-1] if got else ""


def test_sim_launch_gui_true_opens_the_operator_window_that_sends_gestures(stack, video_gesture):
    import rospy
    from std_msgs.msg import Header

    rospy.init_node("test_sim_gui", anonymous=True, disable_signals=True)
    beats = []
    rospy.Subscriber("/rbd_local/heartbeat", Header, beats.append)
    env = dict(os.environ, DISPLAY=stack["display"])

    def window():
        proc = subprocess.run(["xdotool", "search", "--name", "RoboDog operator"], env=env, capture_output=True,
                              text=True, timeout=10)
        return proc.stdout.split()

    assert wait_for(window, 120, 0.5), "no operator window on the display (sim.launch gui:=true)"
    assert wait_for(lambda: len(beats) >= 2, 60), "the operator GUI's heartbeat does not reach ROS"
    assert beats[-1].frame_id == "rbd_local"
    shot = stack["out"] / "sim_gui.png"
    subprocess.run(["import", "-window", window()[0], str(shot)], env=env, check=True, timeout=30)
    from PIL import Image

    assert Image.open(shot).size[0] >= 1000
    # the gesture recognised in the clip reached rbd_gestrec (taken by the fixture)
    assert video_gesture == "walk", "the GUI's gesture from the video never arrived (last: %r)" % video_gesture
    assert stack["launch"].poll() is None


def test_next_five_moves_of_the_new_tricks_in_the_gui(stack, video_gesture):
    import customtkinter as ctk
    import rospy

    from rbd_local.gui.app import OperatorGui
    from rbd_local.link import RobotLink
    from rbd_msgs.srv import GetLastGesture

    with open(os.path.join(ROOT, "src", "rbd_navigation", "config", "tricks.yaml")) as fh:
        tricks = yaml.safe_load(fh)["tricks"]
    root = ctk.CTk()
    holder = {}
    link = RobotLink("127.0.0.1", stack["port"], retry_s=0.3,
                     on_status=lambda s: holder["gui"].post_status(s), on_state=lambda s: holder["gui"].post_state(s),
                     on_path_queue=lambda n: holder["gui"].post_path_queue(n),
                     on_connection=lambda up: holder["gui"].post_connection(up))
    gui = holder["gui"] = OperatorGui(root, link)
    shown = []  # every list the window showed (several queue messages may land in one Tk update)
    show_moves = gui._show_moves

    def recording(names):
        show_moves(names)
        shown.append(gui.shown_moves())

    gui._show_moves = recording
    # the stack's own GUI's video gesture is taken before the e-stop is released here
    assert video_gesture == "walk", "the stack's GUI never sent its video gesture (last: %r)" % video_gesture
    rospy.wait_for_service("/rbd_gestrec/get_last_gesture", timeout=60)
    last = rospy.ServiceProxy("/rbd_gestrec/get_last_gesture", GetLastGesture)
    link.start()
    try:
        assert wait_for(_pumped(root, lambda: link.connected), 30)
        ok, msg = link.em_stop(False, timeout=10)
        assert ok, msg
        for trick in NEW_TRICKS:
            assert wait_for(_pumped(root, lambda: gui.state == "WAITING_FOR_GESTURE"), 60), (trick, gui.state)
            expected = ["%d. %s" % (i + 1, s["name"]) for i, s in enumerate(tricks[trick][:5])]
            expected += [""] * (5 - len(expected))
            for _attempt in range(3):  # the bridge's first message on a new publisher may be lost
                last()  # nothing left over in rbd_gestrec
                link.send_gesture(trick)  # as the laptop does for a taught gesture of this trick
                if wait_for(_pumped(root, lambda: gui.state == "EXECUTING"), 10):
                    break
            assert gui.state == "EXECUTING", (trick, gui.state)
            assert wait_for(_pumped(root, lambda: gui.state == "WAITING_FOR_GESTURE"), 90), (trick, gui.state)
            assert wait_for(_pumped(root, lambda: shown[-1][0] == "(no moves queued)"), 10), shown[-3:]
            # the window showed the trick's first five moves, then each reached move dropped off
            history = shown[:]
            del shown[:]
            assert expected in history, (trick, expected, history)
            after = history[history.index(expected):]
            second = ["%d. %s" % (i + 1, s["name"]) for i, s in enumerate(tricks[trick][1:6])]
            assert second + [""] * (5 - len(second)) in after, (trick, after)
    finally:
        link.stop()
        root.destroy()
