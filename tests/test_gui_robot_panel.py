"""The robot panel says when the link in use was lost, how often, and for how long in all."""

from __future__ import annotations

import pytest

pytest.importorskip("pytestqt")

from badminton_gui.gui.robot_panel import RobotLinkPanel  # noqa: E402
from badminton_gui.io.robot_link import RobotLink  # noqa: E402

from .test_robot_link import VanishingPort, wait_for  # noqa: E402


def _refuse(*_):
    raise OSError(2, "No such file or directory")


def test_a_lost_link_is_shown_in_the_panel(qtbot):
    panel = RobotLinkPanel("/dev/robot")
    qtbot.addWidget(panel)
    ports = [VanishingPort(good_writes=1)]
    link = RobotLink("/dev/robot", heartbeat_s=0.05,
                     serial_factory=lambda *a: ports.pop() if ports else _refuse())
    panel.link = link
    try:
        assert wait_for(lambda: link.status().outages == 1)
        panel.refresh()
        text = panel.status.text()
        assert "lost, reopening the port" in text
        assert "lost 1×" in text
        assert "Input/output error" in text or "No such file" in text
    finally:
        panel.link = None
        link.close()
