"""Screenshots of the operator's views that `badminton-gui --screenshot` cannot reach.

Why this file exists: the issue asks for pictures of the tuning dialog and of the optional feed
overlays (foreground mask, rejected candidates coloured and labelled by filter, the trace panel
of the rules that fired), which need menus opened.
This drives the real MainWindow on the demo court, with its own throw-away settings file, and
saves PNGs. Run under Xvfb:

    QT_QPA_PLATFORM=xcb xvfb-run -a -s "-screen 0 1600x900x24" \
        .venv/bin/python scripts/gui-screenshots.py --out /tmp
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=".", help="folder for the PNG files")
    ap.add_argument("--seconds", type=float, default=6.0, help="tracking time before the first picture")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("BADMINTON_GUI_SETTINGS",
                          str(Path(tempfile.mkdtemp(prefix="gui-shots-")) / "settings.ini"))

    from PySide6.QtCore import QCoreApplication, Qt
    from PySide6.QtWidgets import QApplication

    from badminton_gui.gui.main_window import MainWindow
    from badminton_gui.gui.settings import SourceSpec

    QCoreApplication.setAttribute(Qt.ApplicationAttribute.AA_ShareOpenGLContexts)
    app = QApplication(sys.argv[:1])
    window = MainWindow(spec=SourceSpec("demo"))
    window.show()

    def run_for(seconds: float, until=None) -> bool:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            app.processEvents()
            if until is not None and until():
                return True
            time.sleep(0.005)
        return until is None

    def busy_frame() -> bool:
        """Both cameras found the shuttle and some candidates were rejected, on a pair tracked
        with the overlay on (so its trace panel is filled): a telling picture."""
        p = window.latest_packet
        if p is None or p.diagnostics is None:
            return False
        r = p.result
        rejected = sum(c.rejected_by is not None for cam in (r.left, r.right) for c in cam.candidates)
        return r.left.detection is not None and r.right.detection is not None and rejected >= 2

    run_for(args.seconds)
    window.mask_action.trigger()
    window.rejected_action.trigger()
    run_for(30.0, busy_frame)
    window.pause_action.trigger()            # hold that frame for the two pictures
    run_for(0.5)
    path = out / "gui3_overlays.png"
    window.grab_window().save(str(path))
    print(f"overlays: {path}")

    window.open_tuning()
    dialog = window._tuning
    dialog.group_list.setCurrentRow(1)       # binarization: the thresholds the operator tunes first
    window.step_action.trigger()             # one more result so the preview fills
    run_for(10.0, lambda: dialog.preview._qimage is not None)
    run_for(0.5)
    path = out / "gui3_tuning.png"
    dialog.grab().save(str(path))
    print(f"tuning: {path}")
    dialog.close()

    def rule_fired() -> bool:
        """A feed's trace panel names a rule of one camera (the phase alone does not count)."""
        heads = [feed.trace_text.splitlines()[0] for feed in (window.left_feed, window.right_feed)
                 if feed.trace_text]
        return any(name.endswith((":left", ":right")) and not name.startswith("phase:")
                   for head in heads for name in head.split(" · "))

    window.mask_action.trigger()             # the labels and the panel without the tint
    window.pause_action.trigger()
    if run_for(60.0, rule_fired):
        window.pause_action.trigger()
        run_for(0.5)
        path = out / "gui3_trace.png"
        window.grab_window().save(str(path))
        print(f"trace: {path}")
    else:
        print("trace: no rule fired within 60 s", file=sys.stderr)
    window.close()
    app.quit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
