"""The built wheel is a working tool outside the checkout: presets, classifiers, demo, track.

Why this file exists: the editable install that scripts/setup.sh makes reads the repository
directly, so it hides a wheel that lacks its resources (it once held only ``py.typed``: presets
listed 0, ``track`` stopped with "no preset 'default'"). Here the wheel is built, installed with
``--no-deps`` into a fresh virtualenv in a temporary folder, and run from there; the third-party
packages come from this test run's own environment through a ``.pth`` line, so nothing is
downloaded but the build backend.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _declared_packages() -> list[str]:
    with open(REPO / "pyproject.toml", "rb") as fh:
        return list(tomllib.load(fh)["tool"]["setuptools"]["packages"])


def test_every_subpackage_is_declared_for_the_wheel():
    """The package list is explicit (resources/ is mapped in), so a new subpackage must be added
    to it; otherwise the wheel would silently lack it."""
    on_disk = sorted(
        ".".join(path.parent.relative_to(REPO).parts)
        for path in (REPO / "badminton_gui").rglob("__init__.py"))
    declared = _declared_packages()
    missing = [name for name in on_disk if name not in declared]
    assert not missing, f"add to [tool.setuptools] packages in pyproject.toml: {missing}"
    for name in declared:
        if name.startswith("badminton_gui.resources"):
            folder = REPO.joinpath("resources", *name.split(".")[2:])
        else:
            folder = REPO.joinpath(*name.split("."))
        assert folder.is_dir(), f"{name} is declared but {folder} does not exist"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out),
                            str(REPO)], capture_output=True, text=True, timeout=300)
    assert build.returncode == 0, build.stdout + build.stderr
    wheels = list(out.glob("badminton_gui-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


def test_wheel_holds_the_shipped_resources_and_licence(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    shipped_files = [p for p in (REPO / "resources").rglob("*") if p.is_file()]
    assert any(p.suffix == ".png" for p in shipped_files)   # the window icon
    for shipped in shipped_files:
        inside = "badminton_gui/resources/" + shipped.relative_to(REPO / "resources").as_posix()
        assert inside in names, f"{inside} is not in the wheel"
    assert any(n.endswith(".dist-info/licenses/LICENSE") or n.endswith(".dist-info/LICENSE")
               for n in names), "LICENSE is not in the wheel's metadata"
    assert not any(n.startswith(("tests/", "benchmarks/")) for n in names)


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    """A fresh venv outside the checkout with only the wheel installed; returns its bin folder."""
    root = tmp_path_factory.mktemp("fresh")
    venv = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    pip = subprocess.run([str(bin_dir / "python"), "-m", "pip", "install", "-q", "--no-deps",
                          "--no-index", str(wheel)], capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stdout + pip.stderr
    site = subprocess.run([str(bin_dir / "python"), "-c",
                           "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    # numpy, OpenCV, Qt… from this environment; a plain path line, so this environment's own
    # .pth files (among them the editable install of the checkout) are not processed.
    Path(site, "_third_party.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return bin_dir


def _run(bin_dir: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    return subprocess.run([str(bin_dir / "badminton-track"), *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)


def test_installed_wheel_imports_from_its_own_folder(installed, tmp_path):
    where = subprocess.run([str(installed / "python"), "-c",
                            "import badminton_gui; print(badminton_gui.__file__, badminton_gui.__version__)"],
                           cwd=tmp_path, capture_output=True, text=True, check=True).stdout
    assert str(REPO) not in where, f"imported the checkout, not the wheel: {where}"
    with open(REPO / "pyproject.toml", "rb") as fh:
        assert where.split()[1] == tomllib.load(fh)["project"]["version"]


def test_installed_wheel_lists_presets_and_tracks_the_demo(installed, tmp_path):
    listed = _run(installed, tmp_path, "presets")
    assert listed.returncode == 0, listed.stderr
    for name in ("default", "coarse", "broadcast"):
        assert name in listed.stdout
    assert "3 presets" in listed.stdout

    demo = _run(installed, tmp_path, "demo", "--out", "demo", "--frames", "40", "--size", "320x240")
    assert demo.returncode == 0, demo.stderr
    made = {p.name for p in (tmp_path / "demo").iterdir()}
    assert {"left.mp4", "right.mp4", "rig.yaml"} <= made, made

    track = _run(installed, tmp_path, "track", "--left", "demo/left.mp4", "--right", "demo/right.mp4",
                 "--calib", "demo/rig.yaml", "-o", "track.csv")
    assert track.returncode == 0, track.stderr
    rows = (tmp_path / "track.csv").read_text().splitlines()
    assert len(rows) == 41, f"{len(rows)} lines: header + one per frame pair expected"

    for preset in ("coarse", "broadcast"):   # each preset's classifier loads from the wheel
        one = _run(installed, tmp_path, "detect", "demo/left.mp4", "--preset", preset,
                   "-o", f"detect-{preset}.csv")
        assert one.returncode == 0, one.stderr


@pytest.mark.gui
@pytest.mark.skipif(not os.environ.get("DISPLAY"), reason="needs an X server (the suite runs under Xvfb)")
def test_installed_wheel_opens_the_window_on_the_demo(installed, tmp_path):
    """The desktop tool from the wheel: its classifier and presets load (no error banner text in
    its log output) and it saves a screenshot of the demo court."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env.update(QT_QPA_PLATFORM="xcb", BADMINTON_GUI_SETTINGS=str(tmp_path / "settings.ini"),
               BADMINTON_GUI_STATE_DIR=str(tmp_path / "state"))
    shot = tmp_path / "window.png"
    run = subprocess.run([str(installed / "badminton-gui"), "--source", "demo", "--screenshot", str(shot),
                          "--quit-after", "4"], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert shot.is_file() and shot.stat().st_size > 10_000
    assert "not found" not in (run.stdout + run.stderr)
