"""The operator window's Preflight panel: is the real robot ready? (rbd_preflight's preflight, issue 16).

The panel never touches the network itself. It is given

- ``run_preflight(timeout) -> report`` (blocking; run off the UI thread): runs the robot's
  checks now, :meth:`rbd_local.link.RobotLink.run_preflight` in the app (None: no Run button);

and receives reports through the thread-safe :meth:`PreflightPanel.post_report` (the link's
latched ``/preflight/report`` subscription delivers the robot's last report right after every
connection). A report is the dict of :func:`rbd_local.link.preflight_report_from_msg`.

It shows one row per check (PASS green, FAIL red, SKIP grey), the measured value and, on FAIL,
what to do; above them the overall READY / NOT READY line and the time of the report. While the
link is down it says so (the last report stays, marked as such) and Run is disabled.
"""

import queue
import time

import customtkinter as ctk

from rbd_local.gui import drain, in_background

STATUS_COLOURS = {"PASS": "#2e7d32", "FAIL": "#c62828", "SKIP": "#757575"}
READY_COLOUR = "#2e7d32"
NOT_READY_COLOUR = "#c62828"
NO_REPORT_COLOUR = "#616161"
HINT_COLOUR = ("#b71c1c", "#ef9a9a")
RUN_TIMEOUT_S = 20.0  # 3 s observation, the clock probe (1-4 s per host), the round trips


def report_time(stamp: float) -> str:
    """The report's time as the panel shows it (local time of this laptop)."""
    if not stamp:
        return "time unknown"
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(stamp))


class PreflightPanel:
    """Builds the Preflight panel in ``parent`` and keeps it up to date (Tk thread, except ``post_*``)."""

    def __init__(self, parent: ctk.CTkFrame, run_preflight: object = None, timeout: float = RUN_TIMEOUT_S) -> None:
        """Create the widgets.

        Args:
            parent: the frame to fill.
            run_preflight: see the module docstring (None: the panel only shows reports).
            timeout: time allowed for one run [s].
        """
        self.parent = parent
        self.run_preflight = run_preflight
        self.timeout = float(timeout)
        self.report: dict = {}
        self.connected = False
        self._running = False
        self._events: queue.Queue = queue.Queue()
        self.rows: list = []  # one (badge, name, value, hint or None) per check
        parent.grid_columnconfigure(0, weight=1)
        parent.grid_rowconfigure(4, weight=1)

        row = ctk.CTkFrame(parent, fg_color="transparent")
        row.grid(row=0, column=0, sticky="ew", padx=8, pady=(8, 4))
        row.grid_columnconfigure(0, weight=1)
        ctk.CTkLabel(row, text="Preflight", font=ctk.CTkFont(size=18, weight="bold")).grid(row=0, column=0,
                                                                                          sticky="w")
        self.run_button = ctk.CTkButton(row, text="Run", width=90, height=32, command=self.on_run,
                                        font=ctk.CTkFont(size=15, weight="bold"))
        self.run_button.grid(row=0, column=1)
        self.ready_label = ctk.CTkLabel(parent, text="no report yet", fg_color=NO_REPORT_COLOUR, text_color="white",
                                        corner_radius=8, height=38, font=ctk.CTkFont(size=20, weight="bold"))
        self.ready_label.grid(row=1, column=0, sticky="ew", padx=8, pady=2)
        self.time_label = ctk.CTkLabel(parent, text="", anchor="w", text_color=("gray25", "gray75"))
        self.time_label.grid(row=2, column=0, sticky="ew", padx=8)
        self.message_label = ctk.CTkLabel(parent, text="", anchor="w", justify="left", wraplength=330)
        self.message_label.grid(row=3, column=0, sticky="ew", padx=8)
        self.rows_frame = ctk.CTkScrollableFrame(parent, fg_color="transparent")
        self.rows_frame.grid(row=4, column=0, sticky="nsew", padx=4, pady=(2, 6))
        self.rows_frame.grid_columnconfigure(1, weight=1)
        self.set_connected(False)

    # ------------------------------------------------ thread-safe inputs (any thread)
    def post_report(self, report: dict) -> None:
        """A report from the robot (the latched topic or a run)."""
        self._events.put(("report", report))

    # ------------------------------------------------------------- Tk thread only
    def set_connected(self, up: bool) -> None:
        """The link came up or went down: enable Run and say so."""
        self.connected = bool(up)
        self._update_button()
        if not self.connected:
            last = " (showing the last report)" if self.report else ""
            self._message("not connected to the robot: preflight unavailable%s" % last, False)
        elif not self._running:
            self._message("" if self.report else "connected: press Run to check the robot", True)

    def on_run(self) -> None:
        """Run button: run the robot's checks now (in a background thread)."""
        if self.run_preflight is None or self._running or not self.connected:
            return
        self._running = True
        self._update_button()
        self._message("running the robot's checks (a few seconds)…", True)

        run = self.run_preflight
        in_background(self._events, "run", lambda: run(self.timeout), "preflight failed", "rbd-gui-preflight")

    def apply_pending(self) -> None:
        """Apply queued inputs (the window's poll calls this)."""
        for kind, value in drain(self._events):
            if kind == "run":
                self._running = False
                self._update_button()
                if isinstance(value, dict):
                    self._show_report(value)
                    self._message("", True)
                else:
                    self._message(str(value), False)
            elif kind == "report" and isinstance(value, dict):
                self._show_report(value)

    def row_texts(self) -> list:
        """(status, name, value, hint) of each row as shown (hint "" unless FAIL)."""
        return [(b.cget("text"), n.cget("text"), v.cget("text"), h.cget("text") if h is not None else "")
                for b, n, v, h in self.rows]

    def row_colour(self, index: int) -> str:
        """Background colour of a row's status badge."""
        return self.rows[index][0].cget("fg_color")

    def summary(self) -> str:
        """The READY / NOT READY line."""
        return self.ready_label.cget("text")

    # ------------------------------------------------------------------ internals
    def _update_button(self) -> None:
        usable = self.run_preflight is not None and self.connected and not self._running
        self.run_button.configure(state="normal" if usable else "disabled",
                                  text="Running…" if self._running else "Run")

    def _message(self, text: str, ok: bool) -> None:
        self.message_label.configure(text=text, text_color=("gray20", "gray80") if ok else HINT_COLOUR)

    def _show_report(self, report: dict) -> None:
        self.report = report
        checks = report.get("checks", [])
        failed = sum(1 for c in checks if c.get("status") == "FAIL")
        if report.get("ready"):
            self.ready_label.configure(text="READY", fg_color=READY_COLOUR)
        else:
            why = "%d FAIL" % failed if failed else "not every check passed"
            self.ready_label.configure(text="NOT READY (%s)" % why, fg_color=NOT_READY_COLOUR)
        self.time_label.configure(text="report of %s, %.1f s observed" % (report_time(report.get("stamp", 0.0)),
                                                                         report.get("duration", 0.0)))
        for widgets in self.rows:
            for w in widgets:
                if w is not None:
                    w.destroy()
        self.rows = []
        grid_row = 0
        for check in checks:
            status = check.get("status", "")
            badge = ctk.CTkLabel(self.rows_frame, text=status, width=48, height=22, corner_radius=6,
                                 fg_color=STATUS_COLOURS.get(status, NO_REPORT_COLOUR), text_color="white",
                                 font=ctk.CTkFont(size=12, weight="bold"))
            badge.grid(row=grid_row, column=0, sticky="nw", padx=(2, 6), pady=1)
            name = ctk.CTkLabel(self.rows_frame, text=check.get("name", ""), anchor="w", height=22,
                                font=ctk.CTkFont(weight="bold"))
            name.grid(row=grid_row, column=1, sticky="ew")
            value = ctk.CTkLabel(self.rows_frame, text=check.get("value", ""), anchor="w", justify="left",
                                 wraplength=270, height=18, text_color=("gray25", "gray75"))
            value.grid(row=grid_row + 1, column=1, sticky="ew")
            hint = None
            grid_row += 2
            if status == "FAIL" and check.get("hint"):
                hint = ctk.CTkLabel(self.rows_frame, text="→ %s" % check["hint"], anchor="w", justify="left",
                                    wraplength=270, height=18, text_color=HINT_COLOUR)
                hint.grid(row=grid_row, column=1, sticky="ew", pady=(0, 2))
                grid_row += 1
            self.rows.append((badge, name, value, hint))
        if not checks:
            self.ready_label.configure(text="NOT READY (no checks)" if not report.get("ready") else "READY")
        if not self.connected:
            self.set_connected(False)
        elif not self._running:
            self._message("", True)
