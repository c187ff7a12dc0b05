"""The Help menu's windows (About, Keyboard shortcuts), the log folder, and the window icon.

Why this file exists: when something goes wrong the operator must find the log, the rigs and
the settings without knowing where this platform keeps them, and whoever helps needs the exact
versions. The main window only adds the menu; what it shows is built here, from the same
functions the program uses to find those folders (io/app_dirs.py, gui/settings.py), so the
About box can never name a folder the program does not use.
"""

from __future__ import annotations

import html
import platform
from pathlib import Path

from PySide6.QtCore import Qt, QUrl
from PySide6.QtGui import QDesktopServices, QGuiApplication, QIcon, QKeySequence
from PySide6.QtWidgets import (QDialog, QDialogButtonBox, QGridLayout, QLabel,
                               QMenuBar, QPushButton, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget)

from ..core.resources import resource_path
from ..io import app_dirs
from .settings import open_settings

PROGRAM_NAME = "Badminton shuttle tracker"
LICENCE = "MIT"
ICON_FILE = "badminton-gui.png"


def _other_shortcuts() -> list[tuple[str, str, str]]:
    """Shortcuts of other windows than the main one, listed with the main window's."""
    from .tuning_dialog import REDO_KEYS, UNDO_KEYS

    def native(keys: tuple[str, ...]) -> str:
        return ", ".join(QKeySequence(k).toString(QKeySequence.SequenceFormat.NativeText) for k in keys)
    return [("Tuning dialog", "Undo a parameter change", native(UNDO_KEYS)),
            ("Tuning dialog", "Redo", native(REDO_KEYS))]


def icon_path() -> Path:
    """The window icon's file, shipped in ``resources/icons/``."""
    return resource_path("icons", ICON_FILE)


def app_icon() -> QIcon:
    """The window icon (a null icon if the file is missing: the window still opens)."""
    return QIcon(str(icon_path()))


def open_folder(folder: Path) -> bool:
    """Show ``folder`` in the desktop's file manager, creating it first if it does not exist
    yet (the log folder before anything was logged, the rigs' folder before the first rig)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        pass                             # the file manager says what is wrong with it
    return QDesktopServices.openUrl(QUrl.fromLocalFile(str(folder)))


def open_log_folder() -> bool:
    """Help ▸ Open log folder."""
    return open_folder(app_dirs.log_dir())


def log_link_html() -> str:
    """"Details in the log: <folder>", the folder a link that opens it (for error banners)."""
    folder = app_dirs.log_dir()
    return (f"Details in the log: <a style='color: white;' href='{QUrl.fromLocalFile(str(folder)).toString()}'>"
            f"{html.escape(str(folder))}</a>")


def settings_file() -> Path:
    """The settings file this program reads and writes (QSettings, INI format)."""
    return Path(open_settings().fileName())


def versions() -> list[tuple[str, str]]:
    """(component, version) of what the program runs on, for a bug report."""
    import cv2
    import numpy
    import PySide6
    from PySide6.QtCore import qVersion

    from .. import __version__
    return [(PROGRAM_NAME, __version__), ("Python", platform.python_version()),
            ("Qt", qVersion()), ("PySide6", PySide6.__version__), ("OpenCV", cv2.__version__),
            ("numpy", numpy.__version__)]


class AboutDialog(QDialog):
    """Help ▸ About: name, version, licence, the folders the program uses, the versions."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(f"About {PROGRAM_NAME}")
        component_versions = versions()
        title = QLabel(f"<h2 style='margin-bottom:0'>{PROGRAM_NAME}</h2>"
                       f"<p>Version {component_versions[0][1]} · Licence {LICENCE}</p>"
                       "<p>Courtside stereo-vision shuttlecock tracking for badminton robots: "
                       "the shuttle's 3D position, speed and landing from two cameras.</p>")
        title.setWordWrap(True)
        self.title = title
        icon = QLabel()
        icon.setPixmap(app_icon().pixmap(96, 96))
        icon.setAlignment(Qt.AlignmentFlag.AlignTop)

        # The folders: each path a link that opens it, with a button that copies it.
        self.folders: dict[str, Path] = {"Rigs": app_dirs.rig_dir(), "Settings": settings_file(),
                                         "Logs": app_dirs.log_dir()}
        self.folder_labels: dict[str, QLabel] = {}
        self.copy_buttons: dict[str, QPushButton] = {}
        grid = QGridLayout()
        grid.setColumnStretch(1, 1)
        for row, (name, path) in enumerate(self.folders.items()):
            grid.addWidget(QLabel(f"<b>{name}</b>"), row, 0)
            # A settings *file*: its link opens the folder it is in.
            folder = path.parent if name == "Settings" else path
            link = QLabel(f"<a href='{QUrl.fromLocalFile(str(folder)).toString()}'>"
                          f"{html.escape(str(path))}</a>")
            link.setTextInteractionFlags(Qt.TextInteractionFlag.TextBrowserInteraction)
            link.linkActivated.connect(lambda _url, folder=folder: open_folder(folder))
            link.setToolTip(f"Open {folder} in the file manager")
            grid.addWidget(link, row, 1)
            copy = QPushButton("Copy")
            copy.setToolTip(f"Copy {path} to the clipboard")
            copy.clicked.connect(lambda _checked=False, path=path: QGuiApplication.clipboard().setText(str(path)))
            grid.addWidget(copy, row, 2)
            self.folder_labels[name] = link
            self.copy_buttons[name] = copy

        self.versions_label = QLabel("<br>".join(f"{html.escape(name)} {html.escape(version)}"
                                                 for name, version in component_versions[1:]))
        self.versions_label.setStyleSheet("color: #888;")
        self.versions_label.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        copy_all = buttons.addButton("Copy versions", QDialogButtonBox.ButtonRole.ActionRole)
        copy_all.setToolTip("Copy the versions and folders, for a bug report")
        copy_all.clicked.connect(lambda: QGuiApplication.clipboard().setText(self.report_text()))

        head = QGridLayout()
        head.addWidget(icon, 0, 0)
        head.addWidget(title, 0, 1)
        head.setColumnStretch(1, 1)
        lay = QVBoxLayout(self)
        lay.addLayout(head)
        lay.addLayout(grid)
        lay.addSpacing(6)
        lay.addWidget(self.versions_label)
        lay.addWidget(buttons)
        self.setMinimumWidth(560)

    def report_text(self) -> str:
        """The versions and the folders as plain text."""
        return "\n".join([f"{name} {version}" for name, version in versions()]
                         + [f"{name}: {path}" for name, path in self.folders.items()])


def shortcut_rows(menu_bar: QMenuBar) -> list[tuple[str, str, str]]:
    """(menu, command, keys) of every menu command with a shortcut, in menu order, then those of
    other windows: read from the menus themselves, so the list cannot go stale."""
    rows: list[tuple[str, str, str]] = []

    def walk(menu, path: str) -> None:
        for action in menu.actions():
            if action.menu() is not None:
                walk(action.menu(), f"{path} ▸ {action.menu().title().replace('&', '')}" if path
                     else action.menu().title().replace("&", ""))
            elif not action.isSeparator():
                keys = ", ".join(k.toString(QKeySequence.SequenceFormat.NativeText)
                                 for k in action.shortcuts() if not k.isEmpty())
                if keys:
                    rows.append((path, action.text().replace("&", ""), keys))

    walk(menu_bar, "")
    return rows + _other_shortcuts()


class ShortcutsDialog(QDialog):
    """Help ▸ Keyboard shortcuts: a table of them."""

    def __init__(self, menu_bar: QMenuBar, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("Keyboard shortcuts")
        rows = shortcut_rows(menu_bar)
        self.table = QTableWidget(len(rows), 3, self)
        self.table.setHorizontalHeaderLabels(["Where", "Command", "Keys"])
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setSelectionMode(QTableWidget.SelectionMode.NoSelection)
        self.table.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        for r, row in enumerate(rows):
            for c, text in enumerate(row):
                self.table.setItem(r, c, QTableWidgetItem(text))
        header = self.table.horizontalHeader()
        header.setStretchLastSection(True)
        # Measured from the texts: the table's own sizing runs before it has its font and elides.
        metrics = self.table.fontMetrics()
        for c, title in enumerate(("Where", "Command", "Keys")):
            self.table.setColumnWidth(c, max(metrics.horizontalAdvance(text)
                                             for text in [title] + [row[c] for row in rows]) + 28)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close)
        buttons.rejected.connect(self.reject)
        lay = QVBoxLayout(self)
        lay.addWidget(self.table)
        lay.addWidget(buttons)
        self.table.resizeRowsToContents()
        width = sum(self.table.columnWidth(c) for c in range(3)) + 50
        height = header.sizeHint().height() + sum(self.table.rowHeight(r) for r in range(len(rows)))
        self.resize(max(520, width), min(700, height + 70))
