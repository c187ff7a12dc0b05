"""One camera feed with the shuttle overlays: red circle, fading trail, rejected candidates.

Why this file exists: the operator's main view. Painting must cost little on the GUI thread:
the worker already shrank the frame to the feed's size and made it 4-channel BGRA,
so here the numpy array is wrapped in a QImage without copying (Format_RGB32, the raster
engine's own layout) and blitted 1:1; the overlays are a few QPainter primitives in
full-resolution coordinates mapped to the widget. Measured with the QPainter raster engine on a
634×357 frame: BGR888 drawn scaled 1.1 ms, RGB32 drawn 1:1 0.04 ms (scripts/gui-timing.py
times the whole path in the running window). 3-channel BGR still works (scaled, slower).

With the rejected-candidates overlay on, an operator tuning the filters reads why: the nearest
rejected candidates to the reported shuttle carry the short name of the filter that refused
them, and a panel in the corner names the rules that fired on the step and what each detector
stage rejected (``set_trace``; worded by ``overlays.trace_lines`` from the worker's result).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QLineF, QPointF, QRectF, QSize, Qt
from PySide6.QtGui import QColor, QFont, QFontMetrics, QImage, QPainter, QPen
from PySide6.QtWidgets import QSizePolicy, QWidget

from ..core.evaluation import Label
from ..core.types import CameraResult
from .overlays import (DETECTION_COLOUR, LABEL_COLOUR, REJECT_STYLE, TRAIL_COLOUR, WINDOW_COLOUR,
                       reject_short, reject_style)
from .worker import TRAIL_SECONDS

CIRCLE_RADIUS = 11.0     # widget px: clearly visible at any zoom
LABEL_GAP, LABEL_ARM = 4.0, 16.0   # widget px: the truth's cross, its arms reaching past the circle
TRAIL_LEVELS = 8         # opacity steps of the fading trail
_BACKGROUND = QColor(20, 20, 24)


_RING_RADIUS = 6.0
_RING_HALF_SIZE = 9                  # widget px from the sprite's centre to its edge
_ring_sprites: dict[tuple[str, float], QImage] = {}
# Rejected candidates that get a label, nearest to the reported shuttle first: on a busy court
# (a player's limbs, shoes and racket, ~10 rings in a cluster) more only hide the picture.
MAX_REJECT_LABELS = 6
# A ring nearer than this (widget px) to a ring of the same filter that comes before it waits
# until the others are labelled: one word per player's cluster of limbs, not six.
REPEAT_GAP = 48.0


def _ring_sprite(colour: QColor, dpr: float) -> QImage:
    """A rejected-candidate ring (dark halo + coloured ring), drawn once per colour."""
    key = (colour.name(), dpr)
    image = _ring_sprites.get(key)
    if image is None:
        side = int(round(2 * _RING_HALF_SIZE * dpr))
        image = QImage(side, side, QImage.Format.Format_ARGB32_Premultiplied)
        image.setDevicePixelRatio(dpr)
        image.fill(Qt.GlobalColor.transparent)
        q = QPainter(image)
        q.setRenderHint(QPainter.RenderHint.Antialiasing, True)
        centre = QPointF(_RING_HALF_SIZE, _RING_HALF_SIZE)
        q.setPen(QPen(QColor(0, 0, 0, 170), 3.6))
        q.drawEllipse(centre, _RING_RADIUS, _RING_RADIUS)
        q.setPen(QPen(colour, 1.8))
        q.drawEllipse(centre, _RING_RADIUS, _RING_RADIUS)
        q.end()
        _ring_sprites[key] = image
    return image


_trail_pen_cache: list[tuple[QPen, QPen]] = []


def _trail_pens() -> list[tuple[QPen, QPen]]:
    """Per fade level 1..TRAIL_LEVELS: (segment pen, dot pen) in the trail colour at its opacity.

    Segments have flat caps (5× cheaper antialiased than round); the round dots cover the joints.
    """
    if not _trail_pen_cache:
        for lv in range(1, TRAIL_LEVELS + 1):
            colour = QColor(TRAIL_COLOUR)
            colour.setAlpha(int(220 * lv / TRAIL_LEVELS))
            _trail_pen_cache.append((QPen(colour, 2.5, Qt.PenStyle.SolidLine, Qt.PenCapStyle.FlatCap),
                                     QPen(colour, 2.5, Qt.PenStyle.SolidLine, Qt.PenCapStyle.RoundCap)))
    return _trail_pen_cache


class FeedView(QWidget):
    """Draws the newest frame of one camera scaled to fit, with the tracking overlays."""

    def __init__(self, title: str, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.title = title
        self.show_rejected = False
        self.show_legend = True
        self.show_window = False     # the windowed-tracking box, with the diagnostic overlays
        self._image: np.ndarray | None = None
        self._qimage: QImage | None = None
        self._display_scale = 1.0
        self._camera: CameraResult | None = None
        self._trail = np.zeros((0, 3))
        self._label: Label | None = None
        self.show_labels = True
        self._message = "no source"
        self._title_cache: dict[tuple, QImage] = {}
        self._label_cache: dict[tuple, QImage] = {}
        self._trace_lines: tuple[str, ...] = ()
        self._panel_cache: tuple[tuple, QImage] | None = None
        self._labels_cache: tuple[CameraResult, tuple, list] | None = None
        self._fonts: _SmallFonts | None = None
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setMinimumSize(240, 160)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)

    def sizeHint(self) -> QSize:
        return QSize(560, 340)

    # ---- data ------------------------------------------------------------------------------
    def set_frame(self, image: np.ndarray, display_scale: float, camera: CameraResult | None,
                  trail: np.ndarray, label: Label | None = None) -> None:
        """Show a BGRA (fast) or BGR display image; overlay coordinates are full-resolution pixels.
        ``label``: where the source's truth puts the shuttle (drawn when ``show_labels``)."""
        h, w = image.shape[:2]
        self._image = image            # keeps the buffer alive while the QImage wraps it
        fmt = QImage.Format.Format_RGB32 if image.ndim == 3 and image.shape[2] == 4 else QImage.Format.Format_BGR888
        self._qimage = QImage(image.data, w, h, image.strides[0], fmt)
        self._display_scale = display_scale
        self._camera = camera
        self._trail = trail
        self._label = label
        self._message = ""
        self.update()

    def set_trace(self, lines) -> None:
        """The trace panel's lines (``overlays.trace_lines``), drawn with the rejected
        candidates; () for none."""
        lines = tuple(lines)
        if lines != self._trace_lines:
            self._trace_lines = lines
            self.update()

    @property
    def trace_text(self) -> str:
        """The trace panel as it reads, one line per row ("" when it has none)."""
        return "\n".join(self._trace_lines)

    def show_text(self, text: str) -> None:
        """No picture, only a line of text (this view has no camera for the source)."""
        self._image = self._qimage = self._camera = self._label = None
        self._trail = np.zeros((0, 3))
        self._trace_lines = ()
        self.set_message(text)

    def set_message(self, text: str) -> None:
        """Replace the picture by a line of text (no source, source ended)."""
        self._message = text
        self.update()

    # ---- geometry --------------------------------------------------------------------------
    def image_rect(self) -> QRectF:
        """Where the frame is drawn inside the widget (aspect kept, centred)."""
        if self._qimage is None:
            return QRectF(self.rect())
        iw, ih = self._qimage.width(), self._qimage.height()
        k = min(self.width() / iw, self.height() / ih)
        w, h = iw * k, ih * k
        if abs(w - iw) <= 1.5 and abs(h - ih) <= 1.5:
            # The worker sized the frame for this widget: draw it 1:1 on whole pixels (a plain
            # blit; a fractional scale would make Qt resample every pixel on every paint).
            return QRectF((self.width() - iw) // 2, (self.height() - ih) // 2, iw, ih)
        return QRectF((self.width() - w) / 2, (self.height() - h) / 2, w, h)

    def image_to_widget(self, x: float, y: float) -> QPointF:
        """Full-resolution pixel coordinates → widget coordinates."""
        r = self.image_rect()
        if self._qimage is None:
            return QPointF(x, y)
        k = r.width() / self._qimage.width() * self._display_scale
        return QPointF(r.left() + x * k, r.top() + y * k)

    # ---- painting --------------------------------------------------------------------------
    def paintEvent(self, event) -> None:  # noqa: N802 - Qt naming
        p = QPainter(self)
        if self._qimage is not None:
            r = self.image_rect()
            one_to_one = r.width() == self._qimage.width() and r.height() == self._qimage.height()
        if self._qimage is None or not one_to_one:
            p.fillRect(self.rect(), _BACKGROUND)
        else:
            # Drawn 1:1 on whole pixels: fill only the margins around the (opaque) frame;
            # filling the whole widget and covering it with the frame wrote every pixel twice.
            w, h = self.width(), self.height()
            for band in (QRectF(0, 0, w, r.top()), QRectF(0, r.bottom(), w, h - r.bottom()),
                         QRectF(0, r.top(), r.left(), r.height()),
                         QRectF(r.right(), r.top(), w - r.right(), r.height())):
                if band.width() > 0 and band.height() > 0:
                    p.fillRect(band, _BACKGROUND)
        if self._qimage is not None:
            if one_to_one:
                p.drawImage(r.topLeft(), self._qimage)
            else:
                p.drawImage(r, self._qimage)
            p.setRenderHint(QPainter.RenderHint.Antialiasing, True)
            if self.show_window and self._camera is not None and self._camera.window is not None:
                self._paint_window(p)
            if self.show_rejected and self._camera is not None:
                self._paint_rejected(p)
                self._paint_reject_labels(p)
            self._paint_trail(p)
            if self.show_labels:
                self._paint_label(p)
            self._paint_detection(p)
            if self.show_rejected and self.show_legend:
                self._paint_legend(p)
            if self.show_rejected and self._trace_lines:
                self._paint_trace(p)
        self._paint_title(p)
        if self._message:
            p.setPen(QColor(230, 230, 230))
            f = QFont(self.font())
            f.setPointSizeF(f.pointSizeF() * 1.3)
            p.setFont(f)
            p.drawText(self.rect(), Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap,
                       self._message)
        p.end()

    def title_text(self) -> str:
        """The caption: camera name and whether the shuttle is seen, predicted or missing."""
        text = self.title
        if self._camera is not None:
            d = self._camera.detection
            text += ("  ·  no shuttle" if d is None else
                     "  ·  shuttle predicted from the 3D flight" if d.predicted else "  ·  shuttle found")
        return text

    def _paint_title(self, p: QPainter) -> None:
        p.drawImage(QPointF(6, 6), self._title_image(self.title_text()))

    def _title_image(self, text: str) -> QImage:
        """The caption on its translucent box, drawn once per text (a caption has 3-4 states).

        Laying out and rendering the text on every paint was ~0.2 ms of a ~1 ms feed paint; the
        cached image is blended in one blit (source-over is associative: same picture).
        """
        font = QFont(self.font())
        font.setBold(True)
        dpr = self.devicePixelRatioF()
        key = (text, font.key(), dpr)
        image = self._title_cache.get(key)
        if image is None:
            fm = QFontMetrics(font)
            w, h = fm.horizontalAdvance(text) + 12, fm.height() + 6
            image = QImage(int(np.ceil(w * dpr)), int(np.ceil(h * dpr)), QImage.Format.Format_ARGB32_Premultiplied)
            image.setDevicePixelRatio(dpr)
            image.fill(Qt.GlobalColor.transparent)
            q = QPainter(image)
            box = QRectF(0, 0, w, h)
            q.fillRect(box, QColor(0, 0, 0, 150))
            q.setFont(font)
            q.setPen(QColor(255, 255, 255))
            q.drawText(box, Qt.AlignmentFlag.AlignCenter, text)
            q.end()
            if len(self._title_cache) > 16:       # the font or the screen changed: start afresh
                self._title_cache.clear()
            self._title_cache[key] = image
        return image

    def _paint_detection(self, p: QPainter) -> None:
        if self._camera is None or self._camera.detection is None:
            return
        d = self._camera.detection
        c = self.image_to_widget(d.x, d.y)
        p.setBrush(Qt.BrushStyle.NoBrush)
        # A coasted position (the shuttle over a light or a line, where the detector is blind)
        # is the track's prediction, not a sighting: the operator sees it dashed.
        pen = QPen(DETECTION_COLOUR, 2.0 if d.predicted else 3.0)
        if d.predicted:
            pen.setStyle(Qt.PenStyle.DashLine)
        p.setPen(pen)
        p.drawEllipse(c, CIRCLE_RADIUS, CIRCLE_RADIUS)

    def _paint_label(self, p: QPainter) -> None:
        """The truth's shuttle as a green cross with a gap in the middle: the red circle around
        it says the tracker agrees, a lone cross that it missed, a lone circle a false report."""
        if self._label is None or not self._label[0]:
            return
        c = self.image_to_widget(self._label[1], self._label[2])
        for colour, width in ((QColor(0, 0, 0, 170), 3.6), (LABEL_COLOUR, 1.8)):
            p.setPen(QPen(colour, width))
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                p.drawLine(QPointF(c.x() + dx * LABEL_GAP, c.y() + dy * LABEL_GAP),
                           QPointF(c.x() + dx * LABEL_ARM, c.y() + dy * LABEL_ARM))

    def _to_widget(self, xy: np.ndarray) -> np.ndarray:
        """(N, 2) full-resolution pixels → (N, 2) widget coordinates, in one numpy step."""
        r = self.image_rect()
        k = r.width() / self._qimage.width() * self._display_scale
        return np.column_stack((r.left() + xy[:, 0] * k, r.top() + xy[:, 1] * k))

    def _paint_trail(self, p: QPainter) -> None:
        """Recent detections as fading dots, joined where consecutive hits are close.

        A detection that hops to another object and back would otherwise draw long lines
        across the picture; unjoined dots show the hop for what it is. The fade is drawn in
        TRAIL_LEVELS steps of opacity, each step one drawLines/drawPoints call: a pen per
        segment cost 2.2–2.4 ms for a 60-point trail on the GUI thread, batched 1.0 ms. The
        points are grouped by level with one sort and the pens made once: the Python around the
        drawing was 0.4 of 0.7 ms for a ~40-point trail (demo packets, no tracker running).
        """
        trail = self._trail
        if len(trail) < 2:
            return
        pts = self._to_widget(trail[:, 1:3])
        fade = np.clip(1.0 - (trail[-1, 0] - trail[:-1, 0]) / TRAIL_SECONDS, 0.0, 1.0)
        level = np.ceil(fade * TRAIL_LEVELS).astype(np.intp)          # 0 = faded out
        joined = (np.abs(np.diff(pts, axis=0)).sum(axis=1) < 0.12 * max(self.width(), self.height())).tolist()
        qpts = list(map(QPointF, pts[:, 0].tolist(), pts[:, 1].tolist()))
        order = np.argsort(level, kind="stable")
        # bounds[lv - 1]:bounds[lv] are the positions in order of the points at level lv.
        bounds = np.searchsorted(level[order], np.arange(1, TRAIL_LEVELS + 2)).tolist()
        order = order.tolist()
        p.setBrush(Qt.BrushStyle.NoBrush)
        for lv, (line_pen, dot_pen) in enumerate(_trail_pens(), start=1):
            idx = order[bounds[lv - 1]:bounds[lv]]
            if not idx:
                continue
            seg = [QLineF(qpts[i], qpts[i + 1]) for i in idx if joined[i]]
            if seg:
                p.setPen(line_pen)
                p.drawLines(seg)
            p.setPen(dot_pen)
            p.drawPoints([qpts[i] for i in idx])

    def _paint_window(self, p: QPainter) -> None:
        """The only part of this frame the tracker processed (windowed tracking), dashed and
        labelled: outside it the mask is empty because nobody looked, not because nothing moved."""
        x0, y0, x1, y1 = self._camera.window
        top_left, bottom_right = self.image_to_widget(x0, y0), self.image_to_widget(x1, y1)
        pen = QPen(WINDOW_COLOUR, 1.5)
        pen.setStyle(Qt.PenStyle.DashLine)
        p.setPen(pen)
        p.setBrush(Qt.BrushStyle.NoBrush)
        p.drawRect(QRectF(top_left, bottom_right))
        f = QFont(self.font())
        f.setPointSizeF(max(7.0, f.pointSizeF() * 0.8))
        p.setFont(f)
        p.drawText(QPointF(top_left.x() + 3, top_left.y() - 3), "tracking window")

    def _paint_rejected(self, p: QPainter) -> None:
        """Rejected candidates as rings in their filter's colour, each on a dark halo.

        The halo keeps the colours apart from what lies under them: without it the purple
        motion-gate rings vanished on the magenta mask tint and yellow ones on court lines.
        Each ring is a small pre-drawn image blitted at its place: an antialiased drawEllipse
        cost ~0.1 ms per ring, tens of rings per frame on a busy court.
        """
        dpr = self.devicePixelRatioF()
        half = _RING_HALF_SIZE
        for c in self._camera.candidates:
            if c.rejected_by is None:
                continue
            centre = self.image_to_widget(c.x, c.y)
            p.drawImage(QPointF(centre.x() - half, centre.y() - half),
                        _ring_sprite(reject_style(c.rejected_by)[0], dpr))

    def _paint_legend(self, p: QPainter) -> None:
        fonts = self._small_fonts()
        p.setFont(fonts.small)
        fm = fonts.metrics
        rows = list(REJECT_STYLE.values())
        width = fonts.legend_width
        height = fm.height() * len(rows) + 8
        box = QRectF(self.width() - width - 6, self.height() - height - 6, width, height)
        p.fillRect(box, QColor(0, 0, 0, 160))
        for i, (colour, text) in enumerate(rows):
            y = box.top() + 4 + i * fm.height()
            p.setPen(QPen(colour, 1.6))
            p.drawEllipse(QPointF(box.left() + 10, y + fm.height() / 2), 4.5, 4.5)
            p.setPen(QColor(235, 235, 235))
            p.drawText(QRectF(box.left() + 20, y, width - 22, fm.height()),
                       Qt.AlignmentFlag.AlignVCenter, text)

    # ---- what rejected the candidates, which rules fired -------------------------------------
    def _small_fonts(self) -> _SmallFonts:
        """The legend's and the labels' fonts, their metrics and the words' widths, made once per
        widget font: making them on every paint was most of the labels' cost."""
        key = self.font().key()
        if self._fonts is None or self._fonts.key != key:
            self._fonts = _SmallFonts(key, self.font())
        return self._fonts

    def reject_labels(self) -> list[tuple[str, str, QRectF]]:
        """The labels the rejected-candidates overlay draws on this frame at this size: (word,
        reject code, widget rectangle) each, nearest to the reported shuttle first (else to its
        newest trail point, else to the picture's centre), at most ``MAX_REJECT_LABELS``; a ring
        within ``REPEAT_GAP`` of an earlier ring of the same filter after the others. A label
        sits beside its ring where it covers no other label, ring or the red circle; where no
        side is free of rings it may cover one, and where no side is free of labels it is left out."""
        cam = self._camera
        if cam is None or self._qimage is None:
            return []
        r = self.image_rect()
        fonts = self._small_fonts()
        # The same frame painted again (paused, a resize's repaints): the same labels. The
        # camera result by identity (its mask has no plain ``==``).
        key = (id(cam), len(self._trail), r.x(), r.y(), r.width(), fonts.key)
        if self._labels_cache is not None and self._labels_cache[0] is cam and self._labels_cache[1] == key:
            return self._labels_cache[2]
        placed = self._place_labels(cam, r, fonts)
        self._labels_cache = (cam, key, placed)
        return placed

    def _place_labels(self, cam: CameraResult, bounds: QRectF, fonts: _SmallFonts
                      ) -> list[tuple[str, str, QRectF]]:
        rejected = [c for c in cam.candidates if c.rejected_by is not None]
        if not rejected:
            return []
        if cam.detection is not None:
            ref = (cam.detection.x, cam.detection.y)
        elif len(self._trail):
            ref = (self._trail[-1, 1], self._trail[-1, 2])
        else:
            ref = (cam.image_size[0] / 2.0, cam.image_size[1] / 2.0)
        rejected.sort(key=lambda c: (c.x - ref[0]) ** 2 + (c.y - ref[1]) ** 2)
        centres = self._to_widget(np.array([(c.x, c.y) for c in rejected], float))
        order = _repeats_last([c.rejected_by for c in rejected], centres)
        ring = float(_RING_HALF_SIZE)
        # (x0, y0, x1, y1) of every ring, a little inside the sprite (its halo may be touched).
        rings = np.hstack((centres - (ring - 2), centres + (ring - 2)))
        taken: list[tuple[float, float, float, float]] = []     # placed labels and the red circle
        if cam.detection is not None:
            d = self.image_to_widget(cam.detection.x, cam.detection.y)
            rd = CIRCLE_RADIUS + 2.0
            taken.append((d.x() - rd, d.y() - rd, d.x() + rd, d.y() + rd))
        x_lo, y_lo, x_hi, y_hi = bounds.left(), bounds.top(), bounds.right(), bounds.bottom()
        h = float(fonts.bold_metrics.height())
        placed: list[tuple[str, str, QRectF]] = []
        for i in order:
            if len(placed) >= MAX_REJECT_LABELS:
                break
            c = rejected[i]
            word = reject_short(c.rejected_by)
            w = fonts.word_width(word) + 6.0
            x, y = centres[i]
            spots = [(x + ring, y - h / 2), (x - ring - w, y - h / 2), (x - w / 2, y - ring - h),
                     (x - w / 2, y + ring)]
            clear = [(sx, sy, sx + w, sy + h) for sx, sy in spots
                     if x_lo <= sx and sx + w <= x_hi and y_lo <= sy and sy + h <= y_hi
                     and not any(sx < t[2] and t[0] < sx + w and sy < t[3] and t[1] < sy + h for t in taken)]
            if not clear:
                continue
            covers = _covers(np.array(clear), rings, i)
            box = clear[int(np.argmin(covers))]        # the first free of rings, else the first
            taken.append(box)
            placed.append((word, c.rejected_by, QRectF(box[0], box[1], w, h)))
        return placed

    def _label_image(self, word: str, colour: QColor) -> QImage:
        """A candidate's label (its filter's word in its ring's colour on a dark box), drawn once."""
        fonts = self._small_fonts()
        dpr = self.devicePixelRatioF()
        key = (word, colour.name(), fonts.key, dpr)
        image = self._label_cache.get(key)
        if image is None:
            w, h = fonts.word_width(word) + 6, fonts.bold_metrics.height()
            image = QImage(int(np.ceil(w * dpr)), int(np.ceil(h * dpr)), QImage.Format.Format_ARGB32_Premultiplied)
            image.setDevicePixelRatio(dpr)
            image.fill(QColor(0, 0, 0, 170))
            q = QPainter(image)
            q.setFont(fonts.bold)
            q.setPen(colour)
            q.drawText(QRectF(0, 0, w, h), Qt.AlignmentFlag.AlignCenter, word)
            q.end()
            if len(self._label_cache) > 64:
                self._label_cache.clear()
            self._label_cache[key] = image
        return image

    def _paint_reject_labels(self, p: QPainter) -> None:
        for word, reason, rect in self.reject_labels():
            p.drawImage(rect.topLeft(), self._label_image(word, reject_style(reason)[0]))

    def _paint_trace(self, p: QPainter) -> None:
        """The trace panel at the bottom left, beside the legend; drawn once per text and width
        (a paused frame, a resize repaint the same panel)."""
        fonts = self._small_fonts()
        fm = fonts.metrics
        room = self.width() - 12 - (fonts.legend_width + 12 if self.show_legend else 0)
        room = max(120, room)
        dpr = self.devicePixelRatioF()
        key = (self._trace_lines, room, fonts.key, dpr)
        if self._panel_cache is None or self._panel_cache[0] != key:
            lines = [fm.elidedText(line, Qt.TextElideMode.ElideRight, room - 10) for line in self._trace_lines]
            w = max(fm.horizontalAdvance(line) for line in lines) + 10
            step = fm.lineSpacing() + 1
            h = step * len(lines) + fm.descent() + 6
            image = QImage(int(np.ceil(w * dpr)), int(np.ceil(h * dpr)), QImage.Format.Format_ARGB32_Premultiplied)
            image.setDevicePixelRatio(dpr)
            # Nearly opaque: the panel often lies over the court's white lines.
            image.fill(QColor(0, 0, 0, 190))
            q = QPainter(image)
            q.setFont(fonts.small)
            for i, line in enumerate(lines):
                # The rules and the phase first, brighter: what the operator looks for. Drawn on
                # its baseline, so no box clips a descender ("in_play" read "in play").
                q.setPen(QColor(255, 255, 255) if i == 0 else QColor(215, 215, 215))
                q.drawText(QPointF(5, 3 + fm.ascent() + i * step), line)
            q.end()
            self._panel_cache = (key, image)
        image = self._panel_cache[1]
        p.drawImage(QPointF(6, self.height() - image.height() / dpr - 6), image)


class _SmallFonts:
    """The overlay's small fonts (legend, trace panel; bold: the candidates' labels)."""

    def __init__(self, key: str, font: QFont) -> None:
        self.key = key
        self.small = QFont(font)
        self.small.setPointSizeF(max(7.0, font.pointSizeF() * 0.85))
        self.metrics = QFontMetrics(self.small)
        self.bold = QFont(self.small)
        self.bold.setBold(True)
        self.bold_metrics = QFontMetrics(self.bold)
        self.legend_width = max(self.metrics.horizontalAdvance(t) for _, t in REJECT_STYLE.values()) + 30
        self._widths: dict[str, int] = {}

    def word_width(self, word: str) -> int:
        width = self._widths.get(word)
        if width is None:
            width = self._widths[word] = self.bold_metrics.horizontalAdvance(word)
        return width


def _repeats_last(reasons: list[str], centres: np.ndarray) -> list[int]:
    """Indices of the rings in labelling order: as given, but a ring within ``REPEAT_GAP`` of an
    earlier ring of the same filter after all the others (in their order)."""
    first: list[int] = []
    later: list[int] = []
    for i, reason in enumerate(reasons):
        near = [j for j in first if reasons[j] == reason
                and float(np.hypot(*(centres[i] - centres[j]))) < REPEAT_GAP]
        (later if near else first).append(i)
    return first + later


def _covers(boxes: np.ndarray, rings: np.ndarray, own: int) -> np.ndarray:
    """For each box (rows x0, y0, x1, y1), whether it overlaps any ring (rows alike) but ring
    ``own``."""
    b, r = boxes[:, None, :], rings[None, :, :]
    hit = (b[..., 0] < r[..., 2]) & (r[..., 0] < b[..., 2]) & (b[..., 1] < r[..., 3]) & (r[..., 1] < b[..., 3])
    hit[:, own] = False
    return hit.any(axis=1)
