"""Gesture recognition: MediaPipe key points, window features, logistic-regression classifier."""
