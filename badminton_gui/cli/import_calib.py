"""`badminton-track import-calib --nycu CAM1.cfg CAM2.cfg -o RIG.yaml`."""

from __future__ import annotations

import argparse

import numpy as np

from ..io.nycu import rig_from_nycu
from .common import INPUT_ERRORS, UserError, refuse_output_over_inputs


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("import-calib", help="convert another tool's calibration into a rig file",
                       description="Convert the NYCU per-camera .cfg pair into a rig file "
                                   "(OpenCV FileStorage YAML, with the court pose).")
    p.add_argument("--nycu", nargs=2, metavar=("CAM1.cfg", "CAM2.cfg"), required=True,
                   help="left (CameraReader_1) and right (CameraReader_2) .cfg files")
    p.add_argument("-o", "--output", required=True, help="rig file to write (.yaml)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    refuse_output_over_inputs(args.output, *args.nycu)
    try:
        rig = rig_from_nycu(*args.nycu)
        rig.save(args.output)
    except INPUT_ERRORS as exc:
        raise UserError(str(exc)) from None
    except OSError as exc:
        raise UserError(f"cannot write {args.output}: {exc.strerror or exc}") from None
    centres = rig.camera_centres()
    print(f"rig {rig.image_size[0]}x{rig.image_size[1]}, baseline {rig.baseline:.3f} m, "
          f"cameras at {np.round(centres[0], 2).tolist()} and {np.round(centres[1], 2).tolist()} "
          f"(court frame) -> {args.output}")
    return 0
