"""Main controller FSM: e-stop, gesture to path to poses, collision preemption."""
