"""Shared pytest fixtures. Imports no Qt at module level, so core tests stay Qt-free.

GUI fixtures (used by ``tests/test_gui_*.py``): every test gets its own settings file through
``BADMINTON_GUI_SETTINGS`` (never the user's settings), and ``main_window`` builds a window that
is closed (worker stopped, thread joined) after the test.
"""

from __future__ import annotations

import os
import sys

import pytest


@pytest.fixture(autouse=True)
def isolated_gui_settings(tmp_path, monkeypatch):
    """Point the GUI's QSettings at a file in the test's temporary folder."""
    monkeypatch.setenv("BADMINTON_GUI_SETTINGS", str(tmp_path / "gui-settings.ini"))
    yield tmp_path / "gui-settings.ini"


@pytest.fixture(autouse=True)
def isolated_state_dir(tmp_path, monkeypatch):
    """Logs (and rigs saved outside a checkout) go to the test's temporary folder, never the
    user's home; logging set up by a test is taken down after it."""
    state = tmp_path / "state"
    monkeypatch.setenv("BADMINTON_GUI_STATE_DIR", str(state))
    yield state
    setup = sys.modules.get("badminton_gui.io.logging_setup")
    if setup is not None:
        setup.reset_logging()


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY")) or os.environ.get("QT_QPA_PLATFORM") == "offscreen"


@pytest.fixture(scope="session")
def qapp_cls():
    """pytest-qt's application class, created with shared OpenGL contexts.

    pyqtgraph compiles its shaders once per process; without a shared context group the
    second window's GL view would use programs of a destroyed context (GLError 1281).
    """
    from PySide6.QtCore import QCoreApplication, Qt
    from PySide6.QtWidgets import QApplication

    QCoreApplication.setAttribute(Qt.ApplicationAttribute.AA_ShareOpenGLContexts)
    return QApplication


@pytest.fixture
def main_window(qtbot):
    """A factory for MainWindow instances that are shut down cleanly after the test."""
    from badminton_gui.gui.main_window import MainWindow

    windows = []

    def make(**kwargs):
        kwargs.setdefault("start", False)
        window = MainWindow(**kwargs)
        qtbot.addWidget(window)
        window.resize(1280, 720)
        window.show()
        qtbot.waitExposed(window)
        windows.append(window)
        return window

    yield make
    for window in windows:
        window.close()
        assert window.worker is None and not window._retiring, \
            "closing the window must stop every tracking thread"
