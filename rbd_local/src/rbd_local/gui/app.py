"""The operator window: e-stop, state colour, next five moves, last gesture, connection, teach mode, preflight.

The window never touches the network itself. It is given a *backend* with

- ``em_stop(engage: bool, timeout: float) -> (bool, str)`` (may block; run off the UI thread),
- ``connected`` (bool property) and ``address`` (str),
- optionally ``get_tricks(timeout) -> {trick: [step names]}`` (may block) for the Teach panel,
- optionally ``run_preflight(timeout) -> report`` (may block) for the Preflight panel,

which is :class:`rbd_local.link.RobotLink` in the app and a fake in tests. The Teach panel
(:mod:`rbd_local.gui.teach_panel`) also gets the app's
:class:`~rbd_local.gestures.teach.TeachDesk` when gestures are recognised in the same process. Robot data arrives
through the thread-safe ``post_*`` methods (called from the link's thread) and is applied on
the Tk thread by a periodic poll. The Teach and Preflight panels (:mod:`rbd_local.gui.preflight_panel`)
share the third column as tabs ("Teach" shown first).
"""

import queue
import threading
import time

import customtkinter as ctk

from rbd_local.gui import drain
from rbd_local.robot_names import STATUS_COLLISION, STATUS_EMERGENCY, STATUS_IDLE, STATUS_RUNNING

STATUS_COLOURS = {
    STATUS_EMERGENCY: "#c62828",  # red
    STATUS_COLLISION: "#ef6c00",  # orange
    STATUS_IDLE: "#1565c0",  # blue
    STATUS_RUNNING: "#2e7d32",  # green
}
#: Active collision avoidance (issue 17): the main controller's avoidance states get their own
#: label (the state) and colour over the position controller's status; the e-stop still wins.
AVOIDANCE_COLOURS = {
    "BLOCKED": "#6a1b9a",  # purple: stopped by a static obstacle, avoidance pending
    "ESCAPING": "#00838f",  # teal: stepping away / walking around / dodging
    "AVOIDING": "#00838f",
    "DODGING": "#00838f",
}
UNKNOWN_COLOUR = "#616161"
CONNECTED_COLOUR = "#2e7d32"
DISCONNECTED_COLOUR = "#c62828"
MOVES_SHOWN = 5
RELEASE_CONFIRM_S = 5.0
POLL_MS = 50


class OperatorGui:
    """Builds the window in ``root`` and keeps it up to date."""

    def __init__(self, root: ctk.CTk, backend: object, em_stop_timeout: float = 3.0, teach_desk: object = None,
                 mapped_tricks: tuple = (), no_camera_hint: str = "") -> None:
        """Create the widgets.

        Args:
            root: the CustomTkinter root window.
            backend: see the module docstring.
            em_stop_timeout: time allowed for an e-stop call, reconnection included [s].
            teach_desk: the app's :class:`~rbd_local.gestures.teach.TeachDesk` (None: no gesture
                source in this process; the Teach panel says so).
            mapped_tricks: tricks the built-in gestures trigger (the Teach panel preselects another).
            no_camera_hint: the Teach panel's text when there is no desk.
        """
        self.root = root
        self.backend = backend
        self.em_stop_timeout = float(em_stop_timeout)
        self._events: queue.Queue = queue.Queue()
        self._release_armed_until = 0.0
        self._busy = False
        self.status = ""
        self.state = ""
        self.moves: list[str] = []
        root.title("RoboDog operator")
        root.geometry("1150x520")
        root.grid_columnconfigure(0, weight=1)
        root.grid_columnconfigure(1, weight=1)
        root.grid_columnconfigure(2, weight=1)
        root.grid_rowconfigure(0, weight=1)

        left = ctk.CTkFrame(root)
        left.grid(row=0, column=0, sticky="nsew", padx=8, pady=8)
        left.grid_columnconfigure(0, weight=1)
        self.estop_button = ctk.CTkButton(
            left, text="EMERGENCY STOP", command=self.on_estop, fg_color="#b71c1c", hover_color="#7f0000",
            font=ctk.CTkFont(size=22, weight="bold"), height=70,
        )
        self.estop_button.grid(row=0, column=0, sticky="ew", padx=8, pady=(8, 4))
        self.release_button = ctk.CTkButton(left, text="Release e-stop…", command=self.on_release, height=32)
        self.release_button.grid(row=1, column=0, sticky="ew", padx=8, pady=4)
        self.state_label = ctk.CTkLabel(
            left, text="status: unknown", fg_color=UNKNOWN_COLOUR, text_color="white", corner_radius=8, height=90,
            font=ctk.CTkFont(size=26, weight="bold"),
        )
        self.state_label.grid(row=2, column=0, sticky="ew", padx=8, pady=8)
        self.controller_label = ctk.CTkLabel(left, text="controller: –", anchor="w")
        self.controller_label.grid(row=3, column=0, sticky="ew", padx=8)
        self.gesture_label = ctk.CTkLabel(left, text="last gesture: –", anchor="w",
                                          font=ctk.CTkFont(size=16))
        self.gesture_label.grid(row=4, column=0, sticky="ew", padx=8, pady=4)
        self.message_label = ctk.CTkLabel(left, text="", anchor="w", wraplength=340, justify="left")
        self.message_label.grid(row=5, column=0, sticky="ew", padx=8, pady=4)

        right = ctk.CTkFrame(root)
        right.grid(row=0, column=1, sticky="nsew", padx=8, pady=8)
        right.grid_columnconfigure(0, weight=1)
        self.connection_label = ctk.CTkLabel(right, text="● DISCONNECTED", fg_color=DISCONNECTED_COLOUR,
                                             text_color="white", corner_radius=8, height=36,
                                             font=ctk.CTkFont(size=15, weight="bold"))
        self.connection_label.grid(row=0, column=0, sticky="ew", padx=8, pady=(8, 12))
        ctk.CTkLabel(right, text="Next moves", font=ctk.CTkFont(size=18, weight="bold")).grid(
            row=1, column=0, sticky="w", padx=8)
        self.move_labels = []
        for i in range(MOVES_SHOWN):
            lab = ctk.CTkLabel(right, text="", anchor="w", corner_radius=6, height=34,
                               font=ctk.CTkFont(size=16, weight="bold" if i == 0 else "normal"))
            lab.grid(row=2 + i, column=0, sticky="ew", padx=8, pady=3)
            self.move_labels.append(lab)
        self._show_moves([])

        from rbd_local.gui.preflight_panel import PreflightPanel
        from rbd_local.gui.teach_panel import TeachPanel

        self.tabs = ctk.CTkTabview(root)
        self.tabs.grid(row=0, column=2, sticky="nsew", padx=8, pady=(0, 8))
        teach = self.tabs.add("Teach")
        preflight = self.tabs.add("Preflight")
        # "Teach" is shown first (the first tab added). No tabs.set() here: its delayed clean-up would
        # hide a tab chosen right after the window is built.
        self.teach_panel = TeachPanel(teach, getattr(backend, "get_tricks", None), teach_desk, mapped_tricks,
                                      no_camera_hint)
        self.preflight_panel = PreflightPanel(preflight, getattr(backend, "run_preflight", None))
        self._set_connected(bool(getattr(backend, "connected", False)))
        self.root.after(POLL_MS, self._poll)

    # ------------------------------------------------ thread-safe inputs (any thread)
    def post_status(self, status: str) -> None:
        """New ``/rbd_pos_controller/status`` value."""
        self._events.put(("status", status))

    def post_state(self, state: str) -> None:
        """New ``/rbd_controller/state`` value."""
        self._events.put(("state", state))

    def post_path_queue(self, names: list[str]) -> None:
        """New remaining-move names (next first)."""
        self._events.put(("moves", list(names)))

    def post_gesture(self, gesture: str, command: str, confidence: float) -> None:
        """A gesture was recognised and its command sent."""
        self._events.put(("gesture", (gesture, command, confidence)))

    def post_preflight(self, report: dict) -> None:
        """A preflight report (the robot's latched ``/preflight/report``)."""
        self.preflight_panel.post_report(report)

    def post_connection(self, up: bool) -> None:
        """The link came up or went down."""
        self._events.put(("connection", bool(up)))

    # ------------------------------------------------------------- Tk thread only
    def apply_pending(self) -> None:
        """Apply every queued event now (the poll does this every 50 ms)."""
        for kind, value in drain(self._events):
            if kind == "status":
                self._show_status(value)
            elif kind == "state":
                self.state = value
                self.controller_label.configure(text="controller: %s" % value)
                self._show_status(self.status)
            elif kind == "moves":
                self._show_moves(value)
            elif kind == "gesture":
                gesture, command, conf = value
                self.gesture_label.configure(text="last gesture: %s → %s (%.0f %%)" % (gesture, command, 100 * conf))
            elif kind == "connection":
                self._set_connected(value)
            elif kind == "message":
                text, ok = value
                self.message_label.configure(text=text, text_color=("#1b5e20" if ok else "#c62828"))
            elif kind == "done":
                self._busy = False
                self.estop_button.configure(state="normal")
                self.release_button.configure(state="normal")
        if self._release_armed_until and time.monotonic() > self._release_armed_until:
            self._disarm_release()
        self.teach_panel.apply_pending()
        self.preflight_panel.apply_pending()

    def _poll(self) -> None:
        try:
            self.apply_pending()
            connected = bool(getattr(self.backend, "connected", False))
            if connected != self._connected:
                self._set_connected(connected)
        finally:
            self.root.after(POLL_MS, self._poll)

    def _show_status(self, status: str) -> None:
        self.status = status
        if self.state in AVOIDANCE_COLOURS and status != STATUS_EMERGENCY:
            self.state_label.configure(text=self.state, fg_color=AVOIDANCE_COLOURS[self.state])
            return
        colour = STATUS_COLOURS.get(status, UNKNOWN_COLOUR)
        self.state_label.configure(text=status.upper() if status in STATUS_COLOURS else "status: %s" % status,
                                   fg_color=colour)

    def _show_moves(self, names: list[str]) -> None:
        self.moves = list(names)
        shown = self.moves[:MOVES_SHOWN]
        for i, lab in enumerate(self.move_labels):
            if i < len(shown):
                lab.configure(text="%d. %s" % (i + 1, shown[i]), fg_color=("#bbdefb" if i == 0 else "#e0e0e0"),
                              text_color="black")
            else:
                lab.configure(text="" if i else "(no moves queued)", fg_color="transparent",
                              text_color=("gray40", "gray70"))

    def _set_connected(self, up: bool) -> None:
        if up and not getattr(self, "_connected", False):
            self.teach_panel.reload_tricks()  # the robot's tricks, at every (re)connection
        self._connected = up
        self.preflight_panel.set_connected(up)
        address = getattr(self.backend, "address", "")
        if up:
            self.connection_label.configure(text="● CONNECTED %s" % address, fg_color=CONNECTED_COLOUR)
        else:
            self.connection_label.configure(text="● DISCONNECTED — retrying", fg_color=DISCONNECTED_COLOUR)

    def shown_moves(self) -> list[str]:
        """Texts of the five move rows (for tests and screenshots)."""
        return [lab.cget("text") for lab in self.move_labels]

    def state_colour(self) -> str:
        """Current background colour of the state label."""
        return self.state_label.cget("fg_color")

    # ---------------------------------------------------------------- buttons
    def on_estop(self) -> None:
        """E-stop button: engage, reconnecting first if needed; never blocks the UI."""
        self._disarm_release()
        self._call_em_stop(True)

    def on_release(self) -> None:
        """First click arms the release, a second click within 5 s releases the e-stop."""
        if self._release_armed_until and time.monotonic() <= self._release_armed_until:
            self._disarm_release()
            self._call_em_stop(False)
            return
        self._release_armed_until = time.monotonic() + RELEASE_CONFIRM_S
        self.release_button.configure(text="Confirm release (robot may move)", fg_color="#ef6c00")
        self.message_label.configure(text="Click again within %.0f s to release the e-stop." % RELEASE_CONFIRM_S,
                                     text_color=("#e65100", "#ffb74d"))

    def _disarm_release(self) -> None:
        self._release_armed_until = 0.0
        self.release_button.configure(text="Release e-stop…", fg_color=("#3a7ebf", "#1f538d"))

    def _call_em_stop(self, engage: bool) -> None:
        if self._busy and not engage:
            return
        self._busy = True
        self.release_button.configure(state="disabled")
        what = "e-stop" if engage else "release"
        self.message_label.configure(
            text="sending %s…%s" % (what, "" if getattr(self.backend, "connected", False) else " (reconnecting)"),
            text_color=("gray20", "gray80"))

        def work() -> None:
            try:
                ok, msg = self.backend.em_stop(engage, self.em_stop_timeout)
            except Exception as exc:  # the button must always give an answer
                ok, msg = False, str(exc)
            if engage:
                text = "E-STOP ENGAGED" if ok else "E-STOP FAILED: %s" % (msg or "no answer")
            else:
                text = "e-stop released" if ok else "release failed: %s" % (msg or "no answer")
            self._events.put(("message", (text, ok)))
            self._events.put(("done", None))

        threading.Thread(target=work, name="rbd-gui-estop", daemon=True).start()
