"""The court in 3D (OpenGL) and as a plan and a side view (2D), with flight and landing point.

Why this file exists: the operator sees where the shuttle is and where it will land. The 3D view
(pyqtgraph.opengl) shows the court, the net, the two cameras as small frustums, the current
flight, the position, the predicted path and the landing circle; it can be rotated and zoomed.
The plan and side views are plain 2D plots that show the same data; they are also the whole
display when OpenGL is unavailable (``BADMINTON_GUI_NO_GL=1``, an offscreen platform, or a
context that cannot be created), so the window never depends on a working GL driver.

Note: pyqtgraph 0.14.0 hangs with setAspectLocked(True) combined with setXLink/setYLink,
so the two 2D plots lock their aspect and are deliberately not linked.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt
from PySide6.QtGui import QBrush, QColor, QGuiApplication, QPainterPath, QPen
from PySide6.QtWidgets import QGraphicsEllipseItem, QGraphicsItem, QGraphicsPathItem

from ..core import court
from ..core.rig import StereoRig
from .worker import DisplayPacket

NO_GL_ENV = "BADMINTON_GUI_NO_GL"

FLIGHT_COLOUR = (255, 210, 0)
POSITION_COLOUR = (255, 0, 0)
PREDICTED_COLOUR = (80, 220, 255)
IN_COLOUR = (40, 220, 90)
OUT_COLOUR = (255, 70, 70)
CAMERA_COLOURS = ((0, 200, 255), (255, 140, 0))


def gl_unavailable_reason() -> str:
    """Why the 3D view cannot be used here, or "" when OpenGL looks usable."""
    if os.environ.get(NO_GL_ENV, "").strip() not in ("", "0"):
        return f"3D view off ({NO_GL_ENV} is set)"
    platform = QGuiApplication.platformName()
    if platform in ("offscreen", "minimal", "vnc"):
        return f"3D view needs a display (Qt platform '{platform}')"
    try:
        import OpenGL.GL  # noqa: F401  (PyOpenGL is what pyqtgraph.opengl needs)
        import pyqtgraph.opengl  # noqa: F401
    except ImportError as exc:
        return f"3D view unavailable: {exc}"
    from PySide6.QtGui import QOffscreenSurface, QOpenGLContext
    context = QOpenGLContext()
    if not context.create():
        return "3D view unavailable: no OpenGL context could be created"
    surface = QOffscreenSurface()
    surface.create()
    ok = context.makeCurrent(surface)
    if ok:
        context.doneCurrent()
    surface.destroy()
    if not ok:
        return "3D view unavailable: the OpenGL context does not work on this display"
    return ""


def _court_segments_3d() -> np.ndarray:
    segs = []
    for line in court.court_lines():
        segs += [(*line.start, 0.0), (*line.end, 0.0)]
    return np.array(segs, dtype=float)


def _net_segments_3d() -> np.ndarray:
    posts = court.net_posts()
    w = court.HALF_WIDTH_DOUBLES
    top = court.NET_HEIGHT_POSTS
    bottom = top - court.NET_TOP_OF_MESH_DROP
    segs = [posts[0, 0], posts[0, 1], posts[1, 0], posts[1, 1],
            (-w, 0, top), (0, 0, court.NET_HEIGHT_CENTRE), (0, 0, court.NET_HEIGHT_CENTRE), (w, 0, top),
            (-w, 0, bottom), (w, 0, bottom)]
    for x in np.linspace(-w, w, 13)[1:-1]:          # a hint of mesh
        segs += [(x, 0, bottom), (x, 0, top)]
    return np.array(segs, dtype=float)


def _circle(x: float, y: float, r: float, z: float | None = None, n: int = 48) -> np.ndarray:
    a = np.linspace(0, 2 * math.pi, n)
    pts = [x + r * np.cos(a), y + r * np.sin(a)]
    if z is not None:
        pts.append(np.full(n, z))
    return np.stack(pts, axis=1)


def camera_frustums(rig: StereoRig, depth: float = 0.8) -> list[np.ndarray]:
    """Line segments (2k, 3) of a small frustum per camera, in the rig's output frame."""
    centres = rig.camera_centres()
    rotations = rig.camera_rotations()
    w, h = rig.image_size
    out = []
    for cam, (centre, rot, m) in enumerate(zip(centres, rotations, (rig.M1, rig.M2))):
        corners_px = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=float)
        rays = np.column_stack([(corners_px[:, 0] - m[0, 2]) / m[0, 0],
                                (corners_px[:, 1] - m[1, 2]) / m[1, 1], np.ones(4)])
        corners = centre + (rays * depth) @ rot.T
        segs = []
        for i in range(4):
            segs += [centre, corners[i], corners[i], corners[(i + 1) % 4]]
        out.append(np.array(segs))
    return out


def to_display_frame(pts: np.ndarray, in_court_frame: bool) -> np.ndarray:
    """Points as drawn: court frame as is; left-camera frame (x right, y down, z ahead) → z up."""
    pts = np.asarray(pts, dtype=float).reshape(-1, 3)
    if in_court_frame:
        return pts
    return np.column_stack([pts[:, 0], pts[:, 2], -pts[:, 1]])


def scene_key(packet: DisplayPacket) -> tuple:
    """Everything the court views draw from a packet, as a value: equal keys, same picture.

    Between rallies (no point, the same finished flight) successive packets draw the same thing;
    comparing this key (a few KB of bytes at most) is far cheaper than pyqtgraph's setData and
    the repaint it triggers.
    """
    r = packet.result
    lp = r.flight.prediction
    return (r.in_court_frame, r.point,
            None if lp is None else (lp.x, lp.y, lp.radius, lp.call),
            None if packet.flight is None else (packet.flight.shape, packet.flight.tobytes()),
            None if packet.predicted is None else (packet.predicted.shape, packet.predicted.tobytes()))


def _gl_window_class():
    """pyqtgraph's 3D view on a QOpenGLWindow (class built on first use: it imports OpenGL)."""
    global _GLWindow
    if _GLWindow is None:
        from PySide6.QtOpenGL import QOpenGLWindow
        from pyqtgraph.opengl.GLViewWidget import GLViewMixin

        class GLWindow(GLViewMixin, QOpenGLWindow):
            """GLViewMixin (camera, items, mouse) on a window of its own instead of a QOpenGLWidget."""

            def devicePixelRatioF(self) -> float:   # noqa: N802 - the mixin's Qt-widget name
                return self.devicePixelRatio()

        _GLWindow = GLWindow
    return _GLWindow


_GLWindow = None
_gl_parking = None


def _gl_parking_window():
    """A hidden parent for 3D windows until their container adopts them (see CourtGLView)."""
    global _gl_parking
    if _gl_parking is None:
        from PySide6.QtGui import QWindow
        _gl_parking = QWindow()
    return _gl_parking


class CourtGLView:
    """Factory + updater around a pyqtgraph 3D view (import deferred: it needs OpenGL).

    The view is a QOpenGLWindow in a window container, not pyqtgraph's GLViewWidget (a
    QOpenGLWidget). A QOpenGLWidget switches the whole top-level window to GL composition: every
    repaint of any widget (a feed, a readout label) is uploaded as a texture and the window is
    redrawn through OpenGL — on Mesa's llvmpipe ~11-13 ms of wall time and ~16 ms of CPU per
    display tick, even with the 3D scene unchanged (measured with the demo's packets replayed into
    the window). In its own native window the 3D scene renders alone and the rest of the window
    keeps the plain raster flush.
    """

    def __init__(self) -> None:
        import pyqtgraph.opengl as gl
        from PySide6.QtOpenGL import QOpenGLWindow
        from PySide6.QtWidgets import QWidget

        self._gl = gl
        # Created with a parent, so that C++ owns the window: the container reparents it and
        # deletes it with itself. Created without one, PySide's wrapper owned it as well, and at
        # exit PySide deleted it before the QApplication destroyed the still-open main window,
        # whose container then touched the deleted window (segfault after the GUI tests).
        self.window = _gl_window_class()(QOpenGLWindow.UpdateBehavior.NoPartialUpdate,
                                         _gl_parking_window())
        self.window.setBackgroundColor((18, 20, 26))
        self.window.setCameraPosition(distance=17.5, elevation=26.0, azimuth=-62.0)
        self.window.opts["center"] = pg.Vector(0.0, 0.0, 1.0)
        self.widget = QWidget.createWindowContainer(self.window)
        self.widget.setMinimumSize(280, 200)
        self._court = gl.GLLinePlotItem(pos=_court_segments_3d(), mode="lines",
                                        color=(0.95, 0.95, 0.95, 1.0), width=1.5, antialias=True)
        self._net = gl.GLLinePlotItem(pos=_net_segments_3d(), mode="lines",
                                      color=(0.75, 0.75, 0.8, 0.9), width=1.2, antialias=True)
        floor = np.array([[-4.5, -8.5, -0.01], [4.5, -8.5, -0.01], [4.5, 8.5, -0.01], [-4.5, 8.5, -0.01],
                          [-4.5, -8.5, -0.01]])
        self._floor = gl.GLLinePlotItem(pos=floor, mode="line_strip", color=(0.3, 0.35, 0.4, 1.0))
        self._cameras = [gl.GLLinePlotItem(pos=np.zeros((2, 3)), mode="lines", width=1.5,
                                           color=tuple(c / 255 for c in col) + (1.0,))
                         for col in CAMERA_COLOURS]
        self._flight = gl.GLLinePlotItem(pos=np.zeros((0, 3)), mode="line_strip", width=2.5,
                                         color=tuple(c / 255 for c in FLIGHT_COLOUR) + (1.0,), antialias=True)
        self._predicted = gl.GLLinePlotItem(pos=np.zeros((0, 3)), mode="line_strip", width=2.0,
                                            color=tuple(c / 255 for c in PREDICTED_COLOUR) + (0.9,), antialias=True)
        self._landing = gl.GLLinePlotItem(pos=np.zeros((0, 3)), mode="line_strip", width=2.5,
                                          color=(0.2, 0.9, 0.4, 1.0), antialias=True)
        self._position = gl.GLScatterPlotItem(pos=np.zeros((0, 3)), size=14.0,
                                              color=(1.0, 0.0, 0.0, 1.0), pxMode=True)
        for item in (self._floor, self._court, self._net, *self._cameras, self._flight,
                     self._predicted, self._landing, self._position):
            self.window.addItem(item)
        self._in_court_frame = True
        self._key: tuple | None = None

    def set_rig(self, rig: StereoRig | None) -> None:
        """Draw ``rig``'s cameras (and the court when it has a court pose); None: a source with
        one camera and no rig, whose flight cannot be known (the cameras are hidden)."""
        if rig is None:
            self._key = None
            for item in self._cameras:
                item.setData(pos=np.zeros((0, 3)))
            return
        self._in_court_frame = rig.has_court_pose
        self._key = None
        for item in (self._court, self._net, self._floor):
            item.setVisible(rig.has_court_pose)
        for item, segs in zip(self._cameras, camera_frustums(rig)):
            item.setData(pos=to_display_frame(segs, rig.has_court_pose))
        if not rig.has_court_pose:
            self.window.opts["center"] = pg.Vector(0.0, 6.0, 0.0)

    def show_packet(self, packet: DisplayPacket) -> None:
        key = scene_key(packet)
        if key == self._key:
            return
        self._key = key
        r = packet.result
        cf = r.in_court_frame
        flight = packet.flight
        self._flight.setData(pos=to_display_frame(flight[:, 1:4], cf) if flight is not None and len(flight)
                             else np.zeros((0, 3)))
        pred = packet.predicted
        self._predicted.setData(pos=to_display_frame(pred, cf) if pred is not None and len(pred)
                                else np.zeros((0, 3)))
        self._position.setData(pos=to_display_frame(np.array(r.point), cf) if r.point is not None
                               else np.zeros((0, 3)))
        lp = r.flight.prediction
        if lp is not None and cf:
            colour = IN_COLOUR if lp.call == "in" else OUT_COLOUR if lp.call == "out" else PREDICTED_COLOUR
            self._landing.setData(pos=_circle(lp.x, lp.y, max(lp.radius, 0.05), z=0.01),
                                  color=tuple(c / 255 for c in colour) + (1.0,))
        else:
            self._landing.setData(pos=np.zeros((0, 3)))


def _plot(title: str, x_label: str, y_label: str) -> pg.PlotWidget:
    w = pg.PlotWidget(background=(18, 20, 26))
    # The view's name goes into the axis label, not a title row: these plots are short and
    # wide, and with the aspect locked every pixel of height is court on screen.
    w.setLabel("bottom", f"{title} · {x_label}", units="m")
    w.setLabel("left", y_label, units="m")
    w.showGrid(x=True, y=True, alpha=0.15)
    w.setMenuEnabled(False)
    w.getPlotItem().hideButtons()
    w.setAspectLocked(True)
    w.setMinimumSize(240, 120)
    # The axes draw the grid too, as one QPicture replayed on every repaint of anything under
    # them — the flight moving repaints most of the plot. Replaying it was most of a plot's paint
    # (5-6 ms of ~6 ms on a 360×170 plan, no tracker running); cached as a pixmap it is a blit
    # (1.7 ms), pixel-identical. The range is fixed, so the cache is redrawn only on a resize.
    for name in ("bottom", "left", "top", "right"):
        w.getPlotItem().getAxis(name).setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
    return w


def _path(x, y, connect: str = "all") -> QPainterPath:
    return pg.arrayToQPath(np.asarray(x, dtype=float), np.asarray(y, dtype=float), connect=connect)


class _PlotItems:
    """Adds plain Qt graphics items to a pyqtgraph plot; they paint in C++.

    pyqtgraph's PlotDataItem / ScatterPlotItem paint in Python, so every repaint of the plot
    called back into Python once per item (holding the GIL the tracker's threads need), and
    their setData runs a few hundred lines of Python. A QGraphicsPathItem with a cosmetic pen
    and an ellipse that ignores the view's scale look the same (the plots draw aliased either
    way) and cost one C++ call to move. Measured with the demo's packets replayed into the
    window: both plots' update (new data, repaint, flush) 9.5 -> 2 ms of CPU.
    """

    def __init__(self, plot: pg.PlotWidget) -> None:
        self.plot = plot

    def path(self, colour, width: float, x=(), y=(), connect: str = "all",
             style: Qt.PenStyle = Qt.PenStyle.SolidLine) -> QGraphicsPathItem:
        item = QGraphicsPathItem()
        pen = QPen(QColor(*colour), width, style)
        pen.setCosmetic(True)                     # width in pixels, whatever the zoom
        item.setPen(pen)
        if len(x):
            item.setPath(_path(x, y, connect))
        self.plot.addItem(item)
        return item

    def dot(self, diameter: float, colour, outline=None) -> QGraphicsEllipseItem:
        r = diameter / 2.0
        item = QGraphicsEllipseItem(-r, -r, diameter, diameter)
        item.setFlag(QGraphicsItem.GraphicsItemFlag.ItemIgnoresTransformations)   # pixels, not metres
        item.setBrush(QBrush(QColor(*colour)))
        item.setPen(QPen(QColor(*outline), 1.0) if outline is not None else QPen(Qt.PenStyle.NoPen))
        item.setVisible(False)
        self.plot.addItem(item)
        return item


def _show_path(item: QGraphicsPathItem, x, y) -> None:
    """Draw a polyline through (x, y), or hide the item when there are fewer than two points."""
    if len(x) >= 2:
        item.setPath(_path(x, y))
        item.setVisible(True)
    else:
        item.setVisible(False)


def _show_dot(item: QGraphicsEllipseItem, x: float | None, y: float | None = None) -> None:
    if x is None:
        item.setVisible(False)
    else:
        item.setPos(x, y)
        item.setVisible(True)


def _call_colour(call: str) -> tuple[int, int, int]:
    return IN_COLOUR if call == "in" else OUT_COLOUR if call == "out" else PREDICTED_COLOUR


class CourtPlanView:
    """Top view of the court, Y (along the court) horizontal: flight, landing point, call."""

    def __init__(self) -> None:
        self.widget = _plot("Court plan (top view)", "Y along court", "X")
        items = _PlotItems(self.widget)
        segs = _court_segments_3d()
        # Y horizontal, X vertical: the court is wide on screen like the window.
        items.path((230, 230, 230), 1.2, segs[:, 1], segs[:, 0], connect="pairs")
        w = court.HALF_WIDTH_DOUBLES
        items.path((160, 160, 200), 3, [0, 0], [-w - 0.2, w + 0.2])
        self._flight = items.path(FLIGHT_COLOUR, 2)
        self._predicted = items.path(PREDICTED_COLOUR, 2, style=Qt.PenStyle.DashLine)
        self._circle = items.path(IN_COLOUR, 2)
        # A small centre dot: the uncertainty circle (often 5-20 cm, a few pixels here) stays visible.
        self._landing = items.dot(4, IN_COLOUR)
        self._position = items.dot(11, POSITION_COLOUR, outline=(255, 255, 255))
        self._call = pg.TextItem("", anchor=(0.5, 1.2))
        self._call_shown: tuple[str, tuple] = ("", ())
        self.widget.addItem(self._call)
        self.widget.setRange(xRange=(-7.6, 7.6), yRange=(-3.6, 3.6), padding=0)
        self._key: tuple | None = None

    def show_packet(self, packet: DisplayPacket) -> None:
        key = scene_key(packet)
        if key == self._key:
            return
        self._key = key
        r = packet.result
        cf = r.in_court_frame
        f = packet.flight
        _show_path(self._flight, *((f[:, 2], f[:, 1]) if f is not None and cf else ((), ())))
        p = packet.predicted
        _show_path(self._predicted, *((p[:, 1], p[:, 0]) if p is not None and cf else ((), ())))
        _show_dot(self._position, *((r.point[1], r.point[0]) if r.point is not None and cf else (None,)))
        lp = r.flight.prediction
        if lp is not None and cf:
            colour = _call_colour(lp.call)
            c = _circle(lp.y, lp.x, max(lp.radius, 0.05))
            self._circle.setPen(_cosmetic_pen(colour, 2))
            _show_path(self._circle, c[:, 0], c[:, 1])
            self._landing.setBrush(QBrush(QColor(*colour)))
            _show_dot(self._landing, lp.y, lp.x)
            text = lp.call.upper() or "?"
            if (text, colour) != self._call_shown:
                self._call.setText(text, color=colour)
                self._call_shown = (text, colour)
            self._call.setPos(lp.y, lp.x)
            self._call.setVisible(True)
        else:
            self._circle.setVisible(False)
            self._landing.setVisible(False)
            self._call.setVisible(False)


def _cosmetic_pen(colour, width: float) -> QPen:
    pen = QPen(QColor(*colour), width)
    pen.setCosmetic(True)
    return pen


class SideView:
    """Side view (Y along the court horizontal, height vertical) with the net."""

    def __init__(self) -> None:
        self.widget = _plot("Side view", "Y along court", "height Z")
        items = _PlotItems(self.widget)
        h = court.HALF_LENGTH
        items.path((230, 230, 230), 2, [-h, h], [0, 0])
        items.path((160, 160, 200), 3, [0, 0], [0, court.NET_HEIGHT_POSTS])
        self._flight = items.path(FLIGHT_COLOUR, 2)
        self._predicted = items.path(PREDICTED_COLOUR, 2, style=Qt.PenStyle.DashLine)
        self._position = items.dot(11, POSITION_COLOUR, outline=(255, 255, 255))
        self._landing = items.dot(9, IN_COLOUR)
        self.widget.setRange(xRange=(-7.6, 7.6), yRange=(-0.3, 6.0), padding=0)
        self._key: tuple | None = None

    def show_packet(self, packet: DisplayPacket) -> None:
        key = scene_key(packet)
        if key == self._key:
            return
        self._key = key
        r = packet.result
        cf = r.in_court_frame
        f = packet.flight
        _show_path(self._flight, *((f[:, 2], f[:, 3]) if f is not None and cf else ((), ())))
        p = packet.predicted
        _show_path(self._predicted, *((p[:, 1], p[:, 2]) if p is not None and cf else ((), ())))
        _show_dot(self._position, *((r.point[1], r.point[2]) if r.point is not None and cf else (None,)))
        lp = r.flight.prediction
        _show_dot(self._landing, *((lp.y, 0.0) if lp is not None and cf else (None,)))
