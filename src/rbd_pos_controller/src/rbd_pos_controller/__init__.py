"""Position controller FSM and control law (thesis Eq. 1)."""
