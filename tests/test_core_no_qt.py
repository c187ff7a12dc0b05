"""The core never imports Qt (the CLI runs it headless): import every core module with PySide6 blocked."""

import subprocess
import sys
import textwrap
from pathlib import Path

import badminton_gui.core as core_pkg

CORE_DIR = Path(core_pkg.__file__).parent


def test_core_imports_without_qt():
    modules = sorted(p.stem for p in CORE_DIR.glob("*.py") if p.stem != "__init__")
    assert "tracker" in modules and "detector" in modules
    code = textwrap.dedent(f"""
        import importlib, sys
        class BlockQt:
            def find_spec(self, name, path=None, target=None):
                if name.split('.')[0] in ('PySide6', 'shiboken6', 'pyqtgraph', 'PyQt5', 'PyQt6'):
                    raise ImportError('Qt is blocked in the core: ' + name)
                return None
        sys.meta_path.insert(0, BlockQt())
        for m in {modules!r}:
            importlib.import_module('badminton_gui.core.' + m)
        import badminton_gui
        from badminton_gui import StereoTracker, StereoRig
        leaked = [m for m in sys.modules if m.split('.')[0] in ('PySide6', 'shiboken6', 'pyqtgraph')]
        assert not leaked, leaked
        print('ok', len({modules!r}))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("ok")


def test_core_sources_do_not_mention_qt_imports():
    for path in CORE_DIR.glob("*.py"):
        for line in path.read_text().splitlines():
            stripped = line.strip()
            if stripped.startswith(("import ", "from ")):
                assert "PySide6" not in stripped and "pyqtgraph" not in stripped, (path, line)
