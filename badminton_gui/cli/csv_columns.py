"""What every column of the CSV files the commands write holds, and in which unit.

Why this file exists: the column names are fixed (spreadsheets, TrackNet's tools and our own
`eval` read them), so the units cannot go into the headers; they go into the `--help` of the
commands that write the files, built from these tables. A test checks the tables name exactly
the columns the writers write, so a new column cannot go undocumented.
"""

from __future__ import annotations

COURT_FRAME = ("court frame: origin at the court centre on the floor, X across the court, "
               "Y along it (net at Y = 0), Z up")
LEFT_CAMERA_FRAME = ("left camera's frame: origin at its optical centre, X right, Y down, Z along "
                     "the optical axis")

# `detect` output, `demo`'s left_labels.csv / right_labels.csv (TrackNet's label format).
LABEL_COLUMNS = {
    "Frame": "frame index in the video, from 0",
    "Visibility": "1 shuttle found (labelled), 0 not",
    "X": "px, shuttle centre in the image as recorded, from the left edge; 0 when not visible",
    "Y": "px, from the top edge; 0 when not visible",
}

# `track` output and the GUI's Record (io/labels.py TRACK_COLUMNS); empty cell = no value.
TRACK_COLUMNS = {
    "Frame": "left camera's frame index, from 0",
    "FrameR": "right camera's frame index paired with it",
    "Timestamp": "s, time of the left frame",
    "VisL": "1 shuttle detected in the left image, else 0",
    "XL": "px, left image as recorded (distorted), from the left edge",
    "YL": "px, left image, from the top edge",
    "VisR": "1 shuttle detected in the right image, else 0",
    "XR": "px, right image, from the left edge",
    "YR": "px, right image, from the top edge",
    "Vis3D": "1 a 3D point was found, else 0",
    "X": "m, 3D point: court frame if the rig has a court pose, else the left camera's",
    "Y": "m, 3D point (see X)",
    "Z": "m, 3D point (see X)",
    "Distance": "m, from the left camera to the shuttle (the GUI shows it in mm)",
    "Speed": "m/s, shuttle speed",
    "LandX": "m, predicted landing point, court frame",
    "LandY": "m, predicted landing point, court frame",
    "LandT": "s, predicted landing time, same clock as Timestamp",
    "withheld_reason": "text, why this row's 3D was withheld (clock_stalled: the camera's timestamp "
                       "repeated; no_partner_frame: beyond the other camera's recording; "
                       "input_refused: the tracker refused the pair); empty otherwise",
}

# `demo`'s truth.csv (io/demo_scene.py TRUTH_HEADER): the exact state of every frame.
TRUTH_COLUMNS = {
    "Frame": "frame pair index, from 0",
    "Timestamp": "s, time of the frame pair",
    "Visible": "1 a shuttle is in play, else 0",
    "X": "m, cork centre, court frame; empty when not in play",
    "Y": "m, cork centre, court frame",
    "Z": "m, cork centre, court frame (height above the floor)",
    "VX": "m/s, velocity, court frame",
    "VY": "m/s, velocity, court frame",
    "VZ": "m/s, velocity, court frame",
    "VisL": "1 shuttle visible in the left image (in view, not hidden), else 0",
    "XL": "px, exact projection in the left image, from the left edge",
    "YL": "px, left image, from the top edge",
    "VisR": "1 shuttle visible in the right image, else 0",
    "XR": "px, right image, from the left edge",
    "YR": "px, right image, from the top edge",
    "Shot": "index of the shot in the rally, from 0; -1 no shuttle in play",
    "Kind": "serve, clear, drop, drive or smash; empty when no shuttle in play",
}


def columns_epilog(title: str, columns: dict[str, str]) -> str:
    """A help paragraph listing ``columns`` with their units, one per line (kept as written
    by cli.common.CliHelpFormatter)."""
    width = max(len(name) for name in columns)
    lines = [f"  {name:<{width}}  {text}" for name, text in columns.items()]
    return f"{title}\n" + "\n".join(lines)
