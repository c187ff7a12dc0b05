"""Calibration from two folders of still images (left/, right/), paired by sorted file name.

Why this file exists: the ``calibrate`` CLI and the wizard's "calibrate from two image folders"
button must accept and refuse exactly the same inputs with the same sentences: unequal counts,
no images, an unreadable image, a board found nowhere.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import cv2

from .board import BoardSpec, check_view, detect_board
from .stereo import CalibrationCancelled, CalibrationError, RejectedView, StereoView, \
    pair_detections

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".pgm", ".ppm", ".webp")


def list_images(folder: Path, pattern: str = "*") -> list[Path]:
    folder = Path(folder)
    if not folder.is_dir():
        raise CalibrationError(f"{folder} is not a folder")
    return sorted(p for p in folder.glob(pattern)
                  if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES)


def _split_by_name(images: list[Path]) -> tuple[list[Path], list[Path]]:
    """One folder holding both cameras' images (OpenCV's sample: left01.jpg, right01.jpg …)."""
    left = [p for p in images if "left" in p.name.lower() and "right" not in p.name.lower()]
    right = [p for p in images if "right" in p.name.lower() and "left" not in p.name.lower()]
    return left, right


def pair_image_files(left_dir: Path, right_dir: Path, left_pattern: str = "*",
                     right_pattern: str = "*") -> list[tuple[Path, Path]]:
    """Sorted left images zipped with sorted right images; clear errors when that cannot work.

    When both folders are the same folder and no patterns are given, the images are split by
    name: files whose name contains "left" are the left camera's, "right" the right camera's.
    An image is never paired with itself (that would give a rig with no baseline).
    """
    left = list_images(left_dir, left_pattern)
    right = list_images(right_dir, right_pattern)
    same_folder = Path(left_dir).resolve() == Path(right_dir).resolve()
    if same_folder and left_pattern == "*" and right_pattern == "*":
        by_name = _split_by_name(left)
        if by_name[0] and by_name[1]:
            left, right = by_name
    if not left:
        raise CalibrationError(f"no images ({', '.join(IMAGE_SUFFIXES)}) matching "
                               f"{left_pattern!r} in {left_dir}")
    if not right:
        raise CalibrationError(f"no images ({', '.join(IMAGE_SUFFIXES)}) matching "
                               f"{right_pattern!r} in {right_dir}")
    if len(left) != len(right):
        raise CalibrationError(f"{len(left)} left images but {len(right)} right images: images "
                               f"are paired by sorted file name, so the counts must match")
    pairs = list(zip(left, right))
    for a, b in pairs:
        if a.resolve() == b.resolve():
            raise CalibrationError(
                f"{a.name} would be both the left and the right image of a pair: the two "
                f"folders must hold different images (for one folder holding both cameras' "
                f"images, name them left*/right* or select them by name pattern)")
    return pairs


@dataclass(frozen=True, slots=True)
class FolderViews:
    """Views detected in image pairs, plus the pairs that were skipped and why."""

    views: tuple[StereoView, ...]
    skipped: tuple[RejectedView, ...]
    image_size: tuple[int, int]
    warnings: tuple[RejectedView, ...] = ()     # used, but at the border or blurred


def _read(path: Path):
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise CalibrationError(f"cannot read image {path} (not an image, or damaged)")
    return image


def views_from_pairs(pairs: list[tuple[Path, Path]], spec: BoardSpec,
                     progress: Callable[[float, str], None] | None = None,
                     cancel: Callable[[], bool] | None = None,
                     subpix_half_window: int | None = None) -> FolderViews:
    """Detect the board in every pair; pairs where it fails are skipped with the reason."""
    report = progress or (lambda fraction, text: None)
    views: list[StereoView] = []
    skipped: list[RejectedView] = []
    warnings: list[RejectedView] = []
    size = None
    for index, (left_path, right_path) in enumerate(pairs):
        if cancel is not None and cancel():
            raise CalibrationCancelled("calibration cancelled")
        report(index / len(pairs), f"finding the board in {left_path.name} / {right_path.name}")
        gray_l, gray_r = _read(left_path), _read(right_path)
        view_id = left_path.name if left_path.name == right_path.name else \
            f"{left_path.name}|{right_path.name}"
        for path, gray in ((left_path, gray_l), (right_path, gray_r)):
            this = (gray.shape[1], gray.shape[0])
            if size is None:
                size = this
            elif this != size:
                raise CalibrationError(f"{path} is {this[0]}×{this[1]} but the first image is "
                                       f"{size[0]}×{size[1]}: all images must have one size")
        det_l = detect_board(gray_l, spec, fast_check=False,
                             subpix_half_window=subpix_half_window)
        det_r = detect_board(gray_r, spec, fast_check=False,
                             subpix_half_window=subpix_half_window)
        reasons, notes = [], []
        for name, det, gray in (("left", det_l, gray_l), ("right", det_r, gray_r)):
            # Stills have no previous frame: stillness is judged by the blur check alone.
            # A missing board skips the pair; border and blur only warn, because the
            # outlier rejection of the solve judges such views by their actual error.
            for reason in check_view(det, gray, spec, None, require_still=False):
                if det is None or "corners visible" in reason:
                    reasons.append(f"{name}: {reason}")
                else:
                    notes.append(f"{name}: {reason}")
        if reasons:
            skipped.append(RejectedView(view_id, "; ".join(reasons)))
            continue
        if notes:
            warnings.append(RejectedView(view_id, "; ".join(notes)))
        try:
            views.append(pair_detections(view_id, det_l, det_r, spec))
        except CalibrationError as exc:
            skipped.append(RejectedView(view_id, str(exc)))
    report(1.0, "board detection done")
    if not views:
        raise CalibrationError(f"the {spec.describe()} was not found in both images of any of "
                               f"the {len(pairs)} pairs: check --board (inner corners, e.g. "
                               f"9x6 for a board of 10×7 squares)")
    return FolderViews(tuple(views), tuple(skipped), size, tuple(warnings))
