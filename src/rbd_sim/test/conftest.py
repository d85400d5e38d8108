"""Fixtures for the ROS-free rbd_sim tests."""

import os

import pytest

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture
def worlds_dir():
    return os.path.join(PKG, "worlds")


@pytest.fixture
def pkg_dir():
    return PKG
