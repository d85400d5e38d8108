"""RoboDog laptop app: gesture recognition and operator GUI over roslibpy."""

__version__ = "0.1.0"
