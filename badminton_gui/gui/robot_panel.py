"""The robot link panel: port (serial, Bluetooth SPP such as /dev/rfcomm0, or a pyserial URL
like ``loop://``), baud rate, connect / disconnect and the link's live status.

Why this file exists: the operator must see at a glance whether the robot receives the
coordinates. The link itself (``io/robot_link.py``) never blocks the caller; this panel only
creates / closes it and polls ``status()`` twice a second.
"""

from __future__ import annotations

from PySide6.QtCore import QTimer, Signal
from PySide6.QtWidgets import (QComboBox, QFormLayout, QHBoxLayout, QLabel, QPushButton,
                               QVBoxLayout, QWidget)

BAUD_RATES = (9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)


def _serial_ports() -> list[str]:
    try:
        from serial.tools import list_ports
        ports = [p.device for p in list_ports.comports()]
    except ImportError:
        ports = []
    return ports + ["/dev/rfcomm0", "loop://"]


class RobotLinkPanel(QWidget):
    """Creates the RobotLink and hands it to the main window (which gives it to the worker)."""

    linkChanged = Signal(object)      # RobotLink or None

    def __init__(self, port: str = "", baud: int = 115200, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.link = None
        self.port = QComboBox(editable=True)
        self.port.addItems(_serial_ports())
        self.port.setEditText(port or "/dev/rfcomm0")
        self.port.setToolTip("Serial port, Bluetooth SPP port (/dev/rfcomm0, COM5) or a pyserial URL (loop://)")
        self.baud = QComboBox()
        self.baud.addItems([str(b) for b in BAUD_RATES])
        self.baud.setCurrentText(str(baud))
        self.button = QPushButton("Connect")
        self.button.clicked.connect(self.toggle)
        self.status = QLabel("Not connected")
        self.status.setWordWrap(True)
        form = QFormLayout()
        form.addRow("Port", self.port)
        form.addRow("Baud", self.baud)
        row = QHBoxLayout()
        row.addWidget(self.button)
        row.addStretch(1)
        lay = QVBoxLayout(self)
        lay.addLayout(form)
        lay.addLayout(row)
        lay.addWidget(self.status)
        lay.addStretch(1)
        self._timer = QTimer(self)
        self._timer.timeout.connect(self.refresh)
        self._timer.start(500)

    def toggle(self) -> None:
        if self.link is None:
            self.connect_link()
        else:
            self.disconnect_link()

    def connect_link(self) -> None:
        try:
            from ..io.robot_link import RobotLink
        except ImportError as exc:
            self.status.setText(f"The robot link is not available in this installation ({exc}).")
            return
        try:
            self.link = RobotLink(self.port.currentText().strip(), int(self.baud.currentText()))
        except (ValueError, OSError) as exc:
            self.status.setText(f"Cannot open the link: {exc}")
            return
        self.button.setText("Disconnect")
        self.port.setEnabled(False)
        self.baud.setEnabled(False)
        self.linkChanged.emit(self.link)
        self.refresh()

    def disconnect_link(self) -> None:
        link, self.link = self.link, None
        self.linkChanged.emit(None)        # the worker stops sending before the port closes
        if link is not None:
            link.close()
        self.button.setText("Connect")
        self.port.setEnabled(True)
        self.baud.setEnabled(True)
        self.status.setText("Not connected")

    def refresh(self) -> None:
        if self.link is None:
            return
        s = self.link.status()
        state = "connected" if s.connected else "waiting for the port"
        if not s.connected and s.outages:
            state = "<span style='color:#e66'>lost, reopening the port</span>"
        text = (f"<b>{s.port}</b> @ {s.baud}: {state}<br>"
                f"sent {s.messages_sent}, dropped {s.messages_dropped}, errors {s.errors}<br>"
                f"heartbeats {s.heartbeats_sent}, reconnects {s.reconnects}")
        if s.outages:
            text += f", lost {s.outages}× ({s.seconds_down:.1f} s in all)"
        if s.last_error:
            text += f"<br><span style='color:#e66'>{s.last_error}</span>"
        self.status.setText(text)
