"""The threshold tuning dialog, generated from the parameter dataclasses.

Why this file exists: the operator tunes the pipeline live. Nothing here knows any particular
parameter: every field of every group in ``core/params.py`` becomes a row (slider + spin box
with its range and unit, or a check box, or a choice list) with its help as tooltip, one tab
per group. Each edit makes a new frozen ``TrackerParams`` snapshot; snapshots are
sent at most every 50 ms (≈20 Hz) so dragging a slider never floods the worker.
Beside the controls, a live preview shows the foreground mask with the candidates coloured by
the filter that rejected them. Every change can be undone (Ctrl+Z) and redone (Ctrl+Shift+Z), and
Reset goes back to the preset the parameters came from, not to the built-in values.
"""

from __future__ import annotations

import dataclasses
from decimal import Decimal
from pathlib import Path

import cv2
import numpy as np
from PySide6.QtCore import Qt, QTimer, Signal
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (QCheckBox, QComboBox, QDialog, QDoubleSpinBox, QFileDialog,
                               QGridLayout, QHBoxLayout, QLabel, QListWidget, QMenu, QMessageBox,
                               QPushButton, QScrollArea, QSlider, QSpinBox, QSplitter, QStackedWidget,
                               QToolButton, QVBoxLayout, QWidget)

from ..core.params import ParamError, TrackerParams, field_info
from ..io.presets import list_presets, load_preset
from . import settings as st
from .feed_view import FeedView
from .overlays import reject_style
from .worker import DisplayPacket

SEND_INTERVAL_MS = 50          # at most ~20 snapshots per second while a slider moves
MAX_SLIDER_POSITIONS = 2000    # a slider finer than this is useless; the spin box keeps the step
UNDO_LIMIT = 200               # snapshots kept for undo (each is a few kB)
UNDO_KEYS = ("Ctrl+Z",)
REDO_KEYS = ("Ctrl+Shift+Z", "Ctrl+Y")


class ParamsHistory:
    """Undo and redo over whole parameter snapshots: they are frozen, so keeping the earlier
    ones is all an undo needs. Edits of one control while its slider is held make one step."""

    def __init__(self, limit: int = UNDO_LIMIT) -> None:
        self.limit = limit
        self._undo: list[TrackerParams] = []
        self._redo: list[TrackerParams] = []

    def record(self, before: TrackerParams) -> None:
        """A change was made from ``before``: it can be undone; what was undone cannot be redone."""
        self._undo.append(before)
        del self._undo[:-self.limit]
        self._redo.clear()

    def undo(self, current: TrackerParams) -> TrackerParams | None:
        if not self._undo:
            return None
        self._redo.append(current)
        return self._undo.pop()

    def redo(self, current: TrackerParams) -> TrackerParams | None:
        if not self._redo:
            return None
        self._undo.append(current)
        return self._redo.pop()

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    @property
    def can_redo(self) -> bool:
        return bool(self._redo)


def _load_preset_or_file(name_or_path: str) -> TrackerParams:
    """A shipped preset by name, or a parameter file the user chose (whatever its extension)."""
    return TrackerParams.load(name_or_path) if Path(name_or_path).suffix else load_preset(name_or_path)


def _decimals(step: float) -> int:
    return max(0, -Decimal(str(step)).normalize().as_tuple().exponent)


class NumberEditor(QWidget):
    """Slider + spin box for a numeric field with a declared range."""

    def __init__(self, value: float, lo: float, hi: float, step: float | None, unit: str,
                 is_int: bool, on_change) -> None:
        super().__init__()
        self.lo, self.hi, self.is_int = lo, hi, is_int
        self._on_change = on_change
        if step is None:
            step = 1.0 if is_int else (hi - lo) / 1000.0
        positions = int(round((hi - lo) / step))
        self.slider_step = step if positions <= MAX_SLIDER_POSITIONS else (hi - lo) / MAX_SLIDER_POSITIONS
        self.slider = QSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, int(round((hi - lo) / self.slider_step)))
        self.slider.setMinimumWidth(120)
        if is_int:
            self.spin = QSpinBox()
            self.spin.setRange(int(lo), int(hi))
            self.spin.setSingleStep(max(1, int(step)))
        else:
            self.spin = QDoubleSpinBox()
            self.spin.setDecimals(min(6, max(_decimals(step), 1)))
            self.spin.setRange(lo, hi)
            self.spin.setSingleStep(step)
        if unit:
            self.spin.setSuffix(f" {unit}")
        self.spin.setMinimumWidth(105)
        self.spin.setKeyboardTracking(False)
        lay = QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.slider, 1)
        lay.addWidget(self.spin)
        self.set_value(value)
        self.slider.valueChanged.connect(self._slider_moved)
        self.spin.valueChanged.connect(self._spin_changed)

    def set_value(self, value: float) -> None:
        for w in (self.slider, self.spin):
            w.blockSignals(True)
        self.spin.setValue(int(value) if self.is_int else float(value))
        self.slider.setValue(int(round((value - self.lo) / self.slider_step)))
        for w in (self.slider, self.spin):
            w.blockSignals(False)

    def _slider_moved(self, pos: int) -> None:
        value = min(self.hi, self.lo + pos * self.slider_step)
        value = int(round(value)) if self.is_int else value
        self.spin.blockSignals(True)
        self.spin.setValue(value)
        self.spin.blockSignals(False)
        self._on_change(self.spin.value())

    def _spin_changed(self, value) -> None:
        self.slider.blockSignals(True)
        self.slider.setValue(int(round((value - self.lo) / self.slider_step)))
        self.slider.blockSignals(False)
        self._on_change(value)


class TuningDialog(QDialog):
    """Live tuning of every tracker parameter; emits whole snapshots, throttled."""

    paramsChanged = Signal(object)      # TrackerParams
    presetChosen = Signal(str)          # a preset's name, or the .json file it was loaded from

    def __init__(self, params: TrackerParams, parent: QWidget | None = None,
                 preset: str = "default") -> None:
        super().__init__(parent)
        self.setWindowTitle("Tuning — detection thresholds")
        self.params = params
        self.preset = preset                      # what Reset goes back to
        self.history = ParamsHistory()
        self._held_edit: str | None = None        # the control whose slider drag is one undo step
        self.editors: dict[str, QWidget] = {}     # "group.name" → editor (tests drive these)
        self._send_timer = QTimer(self)
        self._send_timer.setSingleShot(True)
        self._send_timer.timeout.connect(lambda: self.paramsChanged.emit(self.params))

        # -- presets row
        self.preset_combo = QComboBox()
        self.preset_combo.addItem("Preset…")
        for name, description in list_presets().items():
            self.preset_combo.addItem(name)
            self.preset_combo.setItemData(self.preset_combo.count() - 1, description, Qt.ItemDataRole.ToolTipRole)
        self.preset_combo.activated.connect(self._preset_chosen)
        load_button = QPushButton("Load…")
        load_button.setToolTip("Load parameters from a JSON preset file")
        load_button.clicked.connect(self._load_file)
        save_button = QPushButton("Save as…")
        save_button.setToolTip("Save the current parameters as a readable JSON preset file")
        save_button.clicked.connect(self._save_file)
        self.undo_button = QPushButton("Undo")
        self.undo_button.setToolTip("Undo the last parameter change (Ctrl+Z)")
        self.undo_button.clicked.connect(self.undo)
        self.redo_button = QPushButton("Redo")
        self.redo_button.setToolTip("Redo the change undone last (Ctrl+Shift+Z)")
        self.redo_button.clicked.connect(self.redo)
        self.undo_action = QAction("Undo", self)
        self.undo_action.setShortcuts([QKeySequence(k) for k in UNDO_KEYS])
        self.undo_action.triggered.connect(self.undo)
        self.redo_action = QAction("Redo", self)
        self.redo_action.setShortcuts([QKeySequence(k) for k in REDO_KEYS])
        self.redo_action.triggered.connect(self.redo)
        for action in (self.undo_action, self.redo_action):
            action.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
            self.addAction(action)
        # Reset: to the preset in use; its menu also offers the built-in values.
        self.reset_button = QToolButton()
        self.reset_button.setPopupMode(QToolButton.ToolButtonPopupMode.MenuButtonPopup)
        self.reset_button.clicked.connect(self.reset_to_preset)
        reset_menu = QMenu(self.reset_button)
        self.defaults_action = reset_menu.addAction("Reset to the built-in defaults",
                                                    lambda: self.set_params(TrackerParams()))
        self.reset_button.setMenu(reset_menu)
        self._show_preset_name()
        top = QHBoxLayout()
        top.addWidget(QLabel("Preset"))
        top.addWidget(self.preset_combo, 1)
        top.addWidget(load_button)
        top.addWidget(save_button)
        top.addStretch(1)
        top.addWidget(self.undo_button)
        top.addWidget(self.redo_button)
        top.addWidget(self.reset_button)
        self._update_history_buttons()

        # -- one page per parameter group, generated; a side list picks the group
        self.group_list = QListWidget()
        self.pages = QStackedWidget()
        for group_name, group in params.groups():
            if not type(group).LIVE:
                continue
            self.group_list.addItem(type(group).TITLE or group_name)
            self.pages.addWidget(self._group_page(group_name, group))
        self.group_list.currentRowChanged.connect(self.pages.setCurrentIndex)
        self.group_list.setCurrentRow(0)
        self.group_list.setFixedWidth(self.group_list.sizeHintForColumn(0) + 24)
        self.tabs = QWidget()
        tl = QHBoxLayout(self.tabs)
        tl.setContentsMargins(0, 0, 0, 0)
        tl.addWidget(self.group_list)
        tl.addWidget(self.pages, 1)

        # -- live preview
        self.preview = FeedView("Mask preview")
        self.preview.show_rejected = True
        self.preview.show_window = True
        self.preview.setMinimumSize(360, 240)
        self.preview_camera = QComboBox()
        self.preview_camera.addItems(["Left camera", "Right camera"])
        self.preview_info = QLabel("")
        self.preview_info.setWordWrap(True)
        right = QWidget()
        rl = QVBoxLayout(right)
        rl.setContentsMargins(0, 0, 0, 0)
        row = QHBoxLayout()
        row.addWidget(QLabel("Preview"))
        row.addWidget(self.preview_camera)
        row.addStretch(1)
        rl.addLayout(row)
        rl.addWidget(self.preview, 1)
        rl.addWidget(self.preview_info)

        split = QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.tabs)
        split.addWidget(right)
        split.setSizes([640, 400])
        lay = QVBoxLayout(self)
        lay.addLayout(top)
        lay.addWidget(split, 1)
        self.resize(1080, 580)

    def _group_page(self, group_name: str, group) -> QWidget:
        page = QWidget()
        grid = QGridLayout(page)
        grid.setColumnStretch(1, 1)
        # The docstring's first paragraph, its line breaks undone (a summary may run over lines).
        doc = " ".join((type(group).__doc__ or "").strip().split("\n\n")[0].split())
        header = QLabel(f"<b>{type(group).TITLE or group_name}</b> — {doc}")
        header.setWordWrap(True)
        header.setStyleSheet("color: #888;")
        grid.addWidget(header, 0, 0, 1, 2)
        for row, (name, f) in enumerate(field_info(group), start=1):
            meta = f.metadata
            path = f"{group_name}.{name}"
            value = getattr(group, name)
            label = QLabel(meta.get("label") or name.replace("_", " "))
            on_change = (lambda v, path=path: self._edited(path, v))
            if "range" in meta:
                lo, hi = meta["range"]
                editor = NumberEditor(value, lo, hi, meta.get("step"), meta.get("unit", ""),
                                      isinstance(f.default, int) and not isinstance(f.default, bool),
                                      on_change)
            elif "options" in meta:
                editor = QComboBox()
                editor.addItems(list(meta["options"]))
                editor.setCurrentText(str(value))
                editor.currentTextChanged.connect(on_change)
            else:
                editor = QCheckBox()
                editor.setChecked(bool(value))
                editor.toggled.connect(on_change)
            tip = meta.get("help", "")
            if "range" in meta:
                lo, hi = meta["range"]
                unit = meta.get("unit", "")
                tip = (tip + "\n" if tip else "") + f"Range {lo:g}–{hi:g} {unit}".rstrip()
            for w in (label, editor):
                w.setToolTip(tip)
            grid.addWidget(label, row, 0)
            grid.addWidget(editor, row, 1)
            self.editors[path] = editor
        grid.setRowStretch(grid.rowCount(), 1)
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        scroll.setFrameShape(QScrollArea.Shape.NoFrame)
        scroll.setWidget(page)
        # Never squeeze the rows: the scroll area is at least as wide as its page wants.
        scroll.setMinimumWidth(page.minimumSizeHint().width() + scroll.verticalScrollBar().sizeHint().width())
        return scroll

    # ---- parameters ------------------------------------------------------------------------
    def _edited(self, path: str, value) -> None:
        before = self.params
        try:
            self.params = self.params.with_value(path, value)
        except ParamError as exc:
            QMessageBox.warning(self, "Tuning", str(exc))
            return
        editor = self.editors.get(path)
        held = isinstance(editor, NumberEditor) and editor.slider.isSliderDown()
        # A slider dragged is one step, however many values it passed through.
        if not (held and self._held_edit == path):
            self.history.record(before)
        self._held_edit = path if held else None
        self._update_history_buttons()
        if not self._send_timer.isActive():
            self._send_timer.start(SEND_INTERVAL_MS)

    def set_params(self, params: TrackerParams) -> None:
        """Show a whole snapshot (preset, file, defaults) and send it; an undo goes back."""
        if params != self.params:
            self.history.record(self.params)
        self._show_params(params)

    def undo(self) -> None:
        """Ctrl+Z: the snapshot before the last change, shown and sent."""
        previous = self.history.undo(self.params)
        if previous is not None:
            self._show_params(previous)

    def redo(self) -> None:
        """Ctrl+Shift+Z: the change undone last, made again."""
        following = self.history.redo(self.params)
        if following is not None:
            self._show_params(following)

    def _update_history_buttons(self) -> None:
        for widget, enabled in ((self.undo_button, self.history.can_undo), (self.undo_action, self.history.can_undo),
                                (self.redo_button, self.history.can_redo), (self.redo_action, self.history.can_redo)):
            widget.setEnabled(enabled)

    def apply_preset(self, name_or_path: str, params: TrackerParams) -> None:
        """Track with a preset's values (``params``, loaded from ``name_or_path``): shown, sent,
        and what Reset goes back to from now on."""
        self.set_preset(name_or_path)
        self.set_params(params)
        self.presetChosen.emit(name_or_path)

    def set_preset(self, name_or_path: str) -> None:
        """What Reset goes back to from now on (the parameters shown stay as they are)."""
        self.preset = name_or_path
        self._show_preset_name()

    def reset_to_preset(self) -> None:
        """Reset: the values of the preset in use (read again: a preset file may have changed)."""
        try:
            params = _load_preset_or_file(self.preset)
        except (ParamError, OSError) as exc:
            QMessageBox.warning(self, "Reset", f"The preset {self.preset} cannot be loaded: {exc}")
            return
        self.set_params(params)

    def _show_preset_name(self) -> None:
        name = Path(self.preset).stem
        self.reset_button.setText(f"Reset to preset '{name}'")
        self.reset_button.setToolTip(f"Every parameter back to the value of the preset '{name}' "
                                     f"({self.preset}); the arrow offers the built-in defaults")

    def _show_params(self, params: TrackerParams) -> None:
        self.params = params
        self._held_edit = None
        self._update_history_buttons()
        for path, editor in self.editors.items():
            value = params.get(path)
            if isinstance(editor, NumberEditor):
                editor.set_value(value)
            elif isinstance(editor, QComboBox):
                editor.blockSignals(True)
                editor.setCurrentText(str(value))
                editor.blockSignals(False)
            else:
                editor.blockSignals(True)
                editor.setChecked(bool(value))
                editor.blockSignals(False)
        self._send_timer.stop()
        self.paramsChanged.emit(self.params)

    def _preset_chosen(self, index: int) -> None:
        if index <= 0:
            return
        name = self.preset_combo.itemText(index)
        try:
            self.apply_preset(name, load_preset(name))
        except ParamError as exc:
            QMessageBox.warning(self, "Preset", str(exc))
        self.preset_combo.setCurrentIndex(0)

    def _load_file(self) -> None:
        settings = st.open_settings()
        path, _ = QFileDialog.getOpenFileName(self, "Load preset", st.dialog_folder(settings, "presets"),
                                              "Presets (*.json)")
        if not path:
            return
        st.remember_dialog_folder(settings, "presets", path)
        try:
            self.apply_preset(path, _load_preset_or_file(path))
        except (ParamError, OSError) as exc:
            QMessageBox.warning(self, "Load preset", str(exc))

    def _save_file(self) -> None:
        settings = st.open_settings()
        path, _ = QFileDialog.getSaveFileName(self, "Save preset",
                                              str(Path(st.dialog_folder(settings, "presets")) / "preset.json"),
                                              "Presets (*.json)")
        if not path:
            return
        st.remember_dialog_folder(settings, "presets", path)
        if not path.endswith(".json"):
            path += ".json"
        try:
            self.params.save(path, description=f"Saved from the tuning dialog ({Path(path).stem})")
        except OSError as exc:
            QMessageBox.warning(self, "Save preset", f"Cannot write {path}: {exc.strerror or exc}")

    # ---- preview ---------------------------------------------------------------------------
    def show_preview(self, packet: DisplayPacket) -> None:
        cam = packet.result.left if self.preview_camera.currentIndex() == 0 else packet.result.right
        if self.preview_camera.currentIndex() == 1 and packet.right is None:
            self.preview.set_message("This source has one camera: choose the left one")
            return
        if cam.mask is None:
            self.preview.set_message("The tracker kept no mask for this frame")
            return
        image = (cv2.cvtColor(cam.mask, cv2.COLOR_GRAY2BGRA) if cam.mask.ndim == 2
                 else cv2.cvtColor(cam.mask, cv2.COLOR_BGR2BGRA))
        if cam.window is not None:
            image = _shade_outside(image, cam.window, cam.mask_scale)
        self.preview.set_frame(image, cam.mask_scale, cam, np.zeros((0, 3)))
        rejected: dict[str, int] = {}
        for c in cam.candidates:
            if c.rejected_by is not None:
                name = reject_style(c.rejected_by)[1]       # the legend's words, not the code
                rejected[name] = rejected.get(name, 0) + 1
        summary = ", ".join(f"{n} {k}" for k, n in sorted(rejected.items())) or "none"
        self.preview_info.setText(f"{len(cam.candidates)} candidates; "
                                  f"{'shuttle found' if cam.detection else 'no shuttle'}; rejected: {summary}")


def _shade_outside(image: np.ndarray, window: tuple[int, int, int, int], mask_scale: float) -> np.ndarray:
    """The mask preview with the part the tracker did not process on this frame (windowed
    tracking) in dark grey, so it is not mistaken for "no foreground" (black)."""
    h, w = image.shape[:2]
    x0, y0, x1, y1 = (int(round(v * mask_scale)) for v in window)
    x0, x1 = max(0, min(w, x0)), max(0, min(w, x1))
    y0, y1 = max(0, min(h, y0)), max(0, min(h, y1))
    shaded = np.full_like(image, 56)
    shaded[..., 3] = 255
    shaded[y0:y1, x0:x1] = image[y0:y1, x0:x1]
    return shaded
