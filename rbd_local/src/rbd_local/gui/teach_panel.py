"""The operator window's Teach panel: pick one of the robot's tricks, name a gesture, press Teach.

The panel never touches the network or the camera itself. It is given

- ``load_tricks(timeout) -> {trick: [step names]}`` (blocking; run off the UI thread): the
  robot's tricks, :meth:`rbd_local.link.RobotLink.get_tricks` in the app;
- ``desk``: a :class:`rbd_local.gestures.teach.TeachDesk` that the gesture thread serves, or
  None when the app has no camera (the panel then says how to start it with one).

The visitor's instructions ("get ready", "show it now") appear in large coloured text, the
shows recorded so far as a bar; the taught gestures are listed with their trick, a live
confidence bar (fed through :meth:`TeachPanel.post_scores` from the gesture thread) and a
button that forgets them; "Undo" restores the model file before its last change.
"""

import queue

import customtkinter as ctk

from rbd_local.gui import drain, in_background

MOVES_PREVIEW = 5
PHASE_COLOURS = {
    "starting": "#f9a825",
    "ready": "#f9a825",  # amber: get ready
    "show": "#2e7d32",  # green: show it now
    "done": "#1565c0",
    "failed": "#c62828",
    "idle": "#616161",
}
PHASE_TITLES = {"starting": "GET READY", "ready": "GET READY", "show": "SHOW IT NOW", "done": "TAUGHT",
                "failed": "NOT TAUGHT", "idle": ""}


class TeachPanel:
    """Builds the Teach panel in ``parent`` and keeps it up to date (Tk thread, except ``post_*``)."""

    def __init__(self, parent: ctk.CTkFrame, load_tricks: object = None, desk: object = None,
                 mapped_tricks: tuple = (), no_camera_hint: str = "") -> None:
        """Create the widgets.

        Args:
            parent: the frame to fill.
            load_tricks: see the module docstring (None: no trick list).
            desk: see the module docstring.
            mapped_tricks: tricks the built-in gestures already trigger (another one is
                preselected).
            no_camera_hint: what to tell the operator when there is no desk.
        """
        self.parent = parent
        self.load_tricks = load_tricks
        self.desk = desk
        self.mapped_tricks = set(mapped_tricks)
        self.tricks: dict = {}
        self.scores: dict = {}
        self._events: queue.Queue = queue.Queue()
        self._loading = False
        self._taught_shown = None
        self._status = {}
        parent.grid_columnconfigure(0, weight=1)
        bold = ctk.CTkFont(size=18, weight="bold")
        ctk.CTkLabel(parent, text="Teach a gesture", font=bold).grid(row=0, column=0, sticky="w", padx=8, pady=(8, 4))

        row = ctk.CTkFrame(parent, fg_color="transparent")
        row.grid(row=1, column=0, sticky="ew", padx=8)
        row.grid_columnconfigure(1, weight=1)
        ctk.CTkLabel(row, text="Trick", width=52, anchor="w").grid(row=0, column=0, sticky="w")
        self.trick_menu = ctk.CTkOptionMenu(row, values=["(no tricks yet)"], command=self._on_trick, state="disabled")
        self.trick_menu.grid(row=0, column=1, sticky="ew")
        self.reload_button = ctk.CTkButton(row, text="↻", width=34, command=self.reload_tricks)
        self.reload_button.grid(row=0, column=2, padx=(4, 0))
        self.preview_label = ctk.CTkLabel(parent, text="", anchor="nw", justify="left", wraplength=330,
                                          text_color=("gray25", "gray75"))
        self.preview_label.grid(row=2, column=0, sticky="ew", padx=12, pady=(2, 4))

        row = ctk.CTkFrame(parent, fg_color="transparent")
        row.grid(row=3, column=0, sticky="ew", padx=8, pady=2)
        row.grid_columnconfigure(1, weight=1)
        ctk.CTkLabel(row, text="Name", width=52, anchor="w").grid(row=0, column=0, sticky="w")
        self.name_entry = ctk.CTkEntry(row, placeholder_text="new gesture, e.g. checkmark")
        self.name_entry.grid(row=0, column=1, sticky="ew")
        ctk.CTkLabel(row, text="Shows", width=52, anchor="w").grid(row=1, column=0, sticky="w", pady=(4, 0))
        self.shows_button = ctk.CTkSegmentedButton(row, values=["3", "4", "5"])
        self.shows_button.set("5")
        self.shows_button.grid(row=1, column=1, sticky="w", pady=(4, 0))

        row = ctk.CTkFrame(parent, fg_color="transparent")
        row.grid(row=4, column=0, sticky="ew", padx=8, pady=(6, 2))
        row.grid_columnconfigure(0, weight=1)
        self.teach_button = ctk.CTkButton(row, text="Teach", command=self.on_teach, height=36,
                                          font=ctk.CTkFont(size=16, weight="bold"))
        self.teach_button.grid(row=0, column=0, sticky="ew")
        self.cancel_button = ctk.CTkButton(row, text="Cancel", width=70, command=self.on_cancel, state="disabled",
                                           fg_color="gray50")
        self.cancel_button.grid(row=0, column=1, padx=(4, 0))

        self.phase_label = ctk.CTkLabel(parent, text="", corner_radius=8, height=40, text_color="white",
                                        font=ctk.CTkFont(size=20, weight="bold"), fg_color="transparent")
        self.phase_label.grid(row=5, column=0, sticky="ew", padx=8, pady=(4, 2))
        self.message_label = ctk.CTkLabel(parent, text="", anchor="w", justify="left", wraplength=330)
        self.message_label.grid(row=6, column=0, sticky="ew", padx=8)
        self.shows_bar = ctk.CTkProgressBar(parent, height=10)
        self.shows_bar.set(0.0)
        self.shows_bar.grid(row=7, column=0, sticky="ew", padx=8, pady=(2, 6))

        ctk.CTkLabel(parent, text="Taught gestures", font=ctk.CTkFont(size=15, weight="bold")).grid(
            row=8, column=0, sticky="w", padx=8)
        self.taught_frame = ctk.CTkFrame(parent, fg_color="transparent")
        self.taught_frame.grid(row=9, column=0, sticky="ew", padx=8)
        self.taught_frame.grid_columnconfigure(1, weight=1)
        self.taught_rows: dict = {}  # name -> (label, bar, forget button)
        self._empty_label = None
        self.undo_button = ctk.CTkButton(parent, text="Undo last change", command=self.on_undo, height=28,
                                         fg_color="gray45")
        self.undo_button.grid(row=10, column=0, sticky="w", padx=8, pady=(6, 8))
        if desk is None:
            for w in (self.teach_button, self.undo_button, self.name_entry):
                w.configure(state="disabled")
            self._show_phase("idle", no_camera_hint or "no camera: teaching needs a gesture source")
        self._show_taught([])

    # ------------------------------------------------ thread-safe inputs (any thread)
    def post_tricks(self, tricks: object) -> None:
        """The robot's tricks ({trick: [step names]}) or an error text."""
        self._events.put(("tricks", tricks))

    def post_scores(self, scores: dict) -> None:
        """The current window's confidences ({gesture: confidence}, the taught ones are shown)."""
        self._events.put(("scores", dict(scores or {})))

    # ------------------------------------------------------------- Tk thread only
    def reload_tricks(self) -> None:
        """Ask the robot for its tricks again (in a background thread)."""
        if self.load_tricks is None or self._loading:
            return
        self._loading = True
        self.trick_menu.configure(state="disabled")
        self.preview_label.configure(text="loading the robot's tricks…")

        load = self.load_tricks
        in_background(self._events, "tricks", lambda: load(3.0), "tricks not loaded", "rbd-gui-tricks")

    def apply_pending(self) -> None:
        """Apply queued inputs and the desk's state (the window's poll calls this)."""
        for kind, value in drain(self._events):
            if kind == "tricks":
                self._loading = False
                self._show_tricks(value)
            elif kind == "scores":
                self.scores = value
                self._show_scores()
        if self.desk is not None:
            status = self.desk.status()
            if status != self._status:
                self._status = status
                self._show_status(status)

    def selected_trick(self) -> str:
        """The trick chosen in the menu ("" when the list is not loaded)."""
        value = self.trick_menu.get()
        return value if value in self.tricks else ""

    def preview(self) -> list[str]:
        """The preview lines shown for the chosen trick (its first five moves)."""
        text = self.preview_label.cget("text")
        return text.splitlines()

    def taught_names(self) -> list[str]:
        """Names of the gestures listed as taught."""
        return list(self.taught_rows)

    def _show_tricks(self, tricks: object) -> None:
        if not isinstance(tricks, dict) or not tricks:
            self.tricks = {}
            self.trick_menu.configure(values=["(no tricks)"], state="disabled")
            self.trick_menu.set("(no tricks)")
            self.preview_label.configure(text=str(tricks) if tricks else "the robot has no tricks")
            return
        current = self.selected_trick()
        self.tricks = dict(tricks)
        names = list(self.tricks)
        self.trick_menu.configure(values=names, state="normal")
        if current not in self.tricks:
            free = [n for n in names if n not in self.mapped_tricks]
            current = (free or names)[0]
        self.trick_menu.set(current)
        self._on_trick(current)

    def _on_trick(self, trick: str) -> None:
        moves = self.tricks.get(trick, [])
        lines = ["%d. %s" % (i + 1, m) for i, m in enumerate(moves[:MOVES_PREVIEW])]
        if len(moves) > MOVES_PREVIEW:
            lines.append("… %d more" % (len(moves) - MOVES_PREVIEW))
        self.preview_label.configure(text="\n".join(lines))

    def on_teach(self) -> None:
        """Teach button: start a session for the chosen trick and name."""
        if self.desk is None:
            return
        trick = self.selected_trick()
        name = self.name_entry.get().strip()
        if not trick:
            self._show_phase("failed", "pick a trick first (the robot's list is not loaded)")
            return
        try:
            self.desk.start(name, trick, int(self.shows_button.get() or 5))
        except ValueError as exc:
            self._show_phase("failed", str(exc))
            return
        self._status = {}  # show the desk's state at the next poll

    def on_cancel(self) -> None:
        """Cancel button: stop the running session, nothing taught."""
        if self.desk is not None:
            self.desk.cancel()

    def on_undo(self) -> None:
        """Undo button: the model file as it was before its last change."""
        if self.desk is not None:
            self.desk.undo()

    def _forget(self, name: str) -> None:
        if self.desk is not None:
            self.desk.forget(name)

    def _show_phase(self, phase: str, message: str) -> None:
        title = PHASE_TITLES.get(phase, "")
        self.phase_label.configure(text=title, fg_color=PHASE_COLOURS.get(phase, "transparent") if title else
                                   "transparent")
        self.message_label.configure(text=message)

    def _show_status(self, st: dict) -> None:
        phase = st.get("phase", "idle")
        running = phase in ("starting", "ready", "show")
        self._show_phase(phase, st.get("message", ""))
        wanted = max(1, int(st.get("shows") or 1))
        self.shows_bar.set(min(1.0, float(st.get("good", 0)) / wanted) if phase != "idle" else 0.0)
        self.teach_button.configure(state="disabled" if running else "normal")
        self.cancel_button.configure(state="normal" if running else "disabled")
        self._show_taught(st.get("taught", []))

    def _show_taught(self, taught: list) -> None:
        key = [tuple(t) for t in taught]
        if key == self._taught_shown:
            return
        self._taught_shown = key
        for label, bar, button in self.taught_rows.values():
            label.destroy()
            bar.destroy()
            button.destroy()
        self.taught_rows = {}
        if not taught:
            label = ctk.CTkLabel(self.taught_frame, text="(none yet)", anchor="w", text_color=("gray40", "gray70"))
            label.grid(row=0, column=0, sticky="w")
            self._empty_label = label
            return
        if self._empty_label is not None:
            self._empty_label.destroy()
            self._empty_label = None
        for i, (name, trick, shows) in enumerate(taught):
            label = ctk.CTkLabel(self.taught_frame, text="%s → %s (%d)" % (name, trick, shows), anchor="w", width=150)
            label.grid(row=i, column=0, sticky="w", pady=1)
            bar = ctk.CTkProgressBar(self.taught_frame, height=12, width=110)
            bar.set(float(self.scores.get(name, 0.0)))
            bar.grid(row=i, column=1, sticky="ew", padx=4)
            button = ctk.CTkButton(self.taught_frame, text="✕", width=28, height=24, fg_color="gray50",
                                   command=lambda n=name: self._forget(n))
            button.grid(row=i, column=2)
            self.taught_rows[name] = (label, bar, button)

    def _show_scores(self) -> None:
        for name, (_label, bar, _button) in self.taught_rows.items():
            bar.set(max(0.0, min(1.0, float(self.scores.get(name, 0.0)))))

    def confidence_of(self, name: str) -> float:
        """The confidence bar's value of a taught gesture (for tests)."""
        return float(self.taught_rows[name][1].get())
