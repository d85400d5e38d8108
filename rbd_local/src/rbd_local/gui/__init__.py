"""Operator GUI (CustomTkinter). Talks to the robot only through a backend object it is given."""
