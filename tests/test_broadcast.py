"""Behaviour added for broadcast (TV) footage, each gated by a parameter that is off by default.

The default preset (the two-camera rig) must not change: every switch here defaults to off, and
the tests check both that the switch does what it says and that it is off by default.
"""

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from badminton_gui.core.association import TrackletAssociator
from badminton_gui.core.detector import CameraDetector
from badminton_gui.core.evaluation import evaluate, tolerance_px
from badminton_gui.core.params import TrackerParams
from badminton_gui.io.labels import read_point_labels
from badminton_gui.io.presets import load_preset

FPS = 30.0


def _two_tracks(candidate_weight: float) -> list[tuple[int, float, float]]:
    """Two tracklets flying side by side; this frame one blob looks like a shuttle, one not."""
    p = TrackerParams().with_value("association.candidate_weight", candidate_weight)
    assoc = TrackletAssociator(p.motion, p.association)
    out = []
    for i in range(8):
        pos = np.array([[100.0 + 30 * i, 300.0], [100.0 + 30 * i, 500.0]])
        scores = np.array([0.6, 0.6]) if i < 7 else np.array([0.95, 0.2])
        out = assoc.update(i / FPS, pos, scores)
    return out


def test_candidate_weight_in_the_presets():
    """On (2) by default: measured on the tuned-on rallies and the demo court. The coarse
    preset keeps it off: its classifier's scores were not measured with it."""
    assert TrackerParams().association.candidate_weight == 2.0
    assert load_preset("default").association.candidate_weight == 2.0
    assert load_preset("coarse").association.candidate_weight == 0.0
    assert load_preset("broadcast").association.candidate_weight == 2.0


def test_candidate_weight_adds_this_frames_quality_to_the_merit():
    plain = _two_tracks(0.0)
    weighted = _two_tracks(2.0)
    assert plain[0][2] >= 0 and plain[1][2] >= 0
    # Off: only the running quality counts. On: the shuttle-like blob gains 2 × 0.95, the other
    # 2 × 0.2, so this frame's looks separate the two tracklets more.
    assert weighted[0][2] - plain[0][2] == pytest.approx(2.0 * 0.95)
    assert weighted[1][2] - plain[1][2] == pytest.approx(2.0 * 0.2)


# ---- real data (skipped without ../shared/data) ----------------------------------------------
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "broadcast"
TUNED_ON_CLIP = DATA / "1_02_01.mp4"   # a tuned-on clip (benchmarks/clips.py), 197 frames


@pytest.mark.skipif(not TUNED_ON_CLIP.is_file(), reason="real data (../shared/data) not available")
def test_broadcast_preset_on_a_real_tv_rally():
    """The broadcast preset on a whole tuned-on TV rally: a regression guard, not the figure
    (benchmarks/accuracy.py --only '1_0|bwf' gives those). It scored 66.8 % before the
    broadcast work and 91 % after; the bound is loose on purpose."""
    labels = read_point_labels(TUNED_ON_CLIP.with_name("1_02_01_ball.csv")).as_dict()
    cap = cv2.VideoCapture(str(TUNED_ON_CLIP))
    det = CameraDetector(load_preset("broadcast"))
    pred = {}
    i = 0
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        d = det.process(frame, i / 30.0, keep_mask=False).detection
        pred[i] = (d is not None, d.x if d else 0.0, d.y if d else 0.0)
        i += 1
    cap.release()
    out = evaluate(pred, {f: v for f, v in labels.items() if f in pred}, tolerance_px(1280))
    assert out.accuracy >= 0.85, out.summary()


def _shuttle_over_still_clutter(history_needs_motion: bool) -> tuple[tuple, tuple, tuple]:
    """A still blob (a shoe) seen for 40 frames; a shuttle flies towards it at 20 px a frame and
    in the last frame their blobs are one, 2 px from both predictions. Returns the last frame's
    (tracklet, motion, merit) and the idents of the shuttle's and the shoe's tracklets."""
    p = load_preset("broadcast").with_value("association.history_needs_motion", history_needs_motion)
    assoc = TrackletAssociator(p.motion, p.association)
    out = []
    for i in range(40):
        shoe = [400.0, 300.0]
        if i < 30:
            out = assoc.update(i / FPS, np.array([shoe]), np.array([0.1]))
            continue
        shuttle = [400.0 - 20 * (39 - i), 300.0]
        if i < 39:
            out = assoc.update(i / FPS, np.array([shoe, shuttle]), np.array([0.1, 0.9]))
            shoe_id, shuttle_id = out[0][0], out[1][0]
            if i == 37:
                assoc.select(shuttle_id)
        else:
            out = assoc.update(i / FPS, np.array([[402.0, 300.0]]), np.array([0.9]))
    return out[0], shuttle_id, shoe_id


def test_still_clutter_does_not_take_a_passing_shuttle_by_its_age():
    """broadcast bwf_00025 51–53, bwf_00001 94: the shuttle's blob passing over a still shoe went
    to the shoe's older tracklet (its history bonus) and the readout lost the shuttle."""
    (ident, _, merit), shuttle_id, shoe_id = _shuttle_over_still_clutter(False)
    assert ident == shoe_id and merit < 0          # the old rule: the shoe claims it
    (ident, _, merit), shuttle_id, shoe_id = _shuttle_over_still_clutter(True)
    assert ident == shuttle_id and merit >= 0      # by distance alone the flight keeps it


def test_history_needs_motion_only_in_the_broadcast_preset():
    """Off on the two-camera rig (its still tracklets that claim by age are mostly the shuttle,
    held or lying: on at rally_11-47-02 the right camera lost 16 frames)."""
    assert TrackerParams().association.history_needs_motion is False
    assert load_preset("default").association.history_needs_motion is False
    assert load_preset("coarse").association.history_needs_motion is False
    assert load_preset("broadcast").association.history_needs_motion is True


def _fly_then_stop(p: TrackerParams, frames: int):
    """Two tracklets fly 30 px a frame for 10 frames, then stay still; the first is followed.
    Returns the last frame's (tracklet, motion, merit) of each."""
    assoc = TrackletAssociator(p.motion, p.association)
    out = []
    for i in range(frames):
        step = min(i, 10)
        pos = np.array([[100.0 + 30 * step, 300.0], [100.0 + 30 * step, 500.0]])
        out = assoc.update(i / FPS, pos, np.array([0.9, 0.9]))
        if i == 5:
            assoc.select(out[0][0])
    return out


def test_only_the_followed_tracklet_gets_the_long_pause():
    """Two tracklets fly, then stop; after the short allowance only the followed one may rest."""
    out = _fly_then_stop(TrackerParams().with_value("association.pause_frames", 2)
                         .with_value("association.followed_pause_frames", 100), 30)
    assert out[0][2] >= 0      # followed: still within its long allowance
    assert out[1][2] < 0       # the other one: its 2-frame allowance is over


def test_default_rests_only_the_followed_tracklet_for_long():
    """The default's two allowances (10 frames for any tracklet, 40 for the followed one):
    30 frames after two tracklets flew and stopped, the followed one (a shuttle lying where it
    landed) may still be reported, the other (clutter that moved and came to rest) may not."""
    p = TrackerParams()
    assert p.association.pause_frames < p.association.followed_pause_frames
    out = _fly_then_stop(p, 40)
    assert out[0][2] >= 0
    assert out[1][2] < 0


def test_broadcast_followed_pause_is_bounded():
    """The TV preset's followed allowance (40 frames, 1.3 s at 30 fps) outlasts the longest rest
    the TV labels mark visible (33 frames) but not a whole clip: at 1000 frames a board's letter
    the follower once took was held as a still blob for all 254 frames of bwf_00027."""
    p = load_preset("broadcast")
    assert p.association.pause_frames < p.association.followed_pause_frames <= 60
    resting = _fly_then_stop(p, 10 + 35)          # 35 frames after the stop: still reported
    assert resting[0][2] >= 0
    stale = _fly_then_stop(p, 10 + 60)            # 60 frames after: no longer
    assert stale[0][2] < 0


def _far_court_flight(n=50, small=range(25, 29)):
    """A TV-sized dot flight (1280×720 at 30 fps, 12 px a frame) that shrinks to a 3 × 3 px
    dot in the ``small`` frames (the far-court shuttle: a blob of 14–19 px contour length, below
    filter 1's 20 px); a static 3 × 3 dot far from the path is there in those frames too."""
    rng = np.random.default_rng(3)
    frames, truth = [], []
    for i in range(n):
        img = np.clip(rng.normal(60, 2, (720, 1280, 3)), 0, 255).astype(np.uint8)
        x, y = 200 + 12 * i, 300
        if i in small:
            img[y - 1:y + 2, x - 1:x + 2] = 240
            img[500:503, 300:303] = 240
        else:
            cv2.circle(img, (x, y), 3, (240, 240, 240), -1)
        frames.append(img)
        truth.append((x, y))
    return frames, truth


@pytest.mark.parametrize("guided", [0.0, None])
def test_broadcast_preset_lets_a_short_blob_through_where_the_followed_shuttle_is_predicted(guided):
    """The broadcast preset uses the default's guided exception to filter 1 (14 px within 12 px
    of the followed shuttle's prediction; measured on the tuned-on TV clips 77.75 -> 79.00 %):
    the far-court shuttle shrinks below the 20 px minimum for a frame or two. Elsewhere a blob
    that short stays rejected. ``guided=0`` is the preset before (the exception off)."""
    p = load_preset("broadcast")
    assert p.contour_length.guided_min_length == 14.0 and p.contour_length.guided_radius == 12.0
    if guided is not None:
        p = p.with_value("contour_length.guided_min_length", guided)
    frames, truth = _far_court_flight()
    det = CameraDetector(p)
    hits = []
    for i, img in enumerate(frames):
        res = det.process(img, i / FPS, keep_mask=False)
        if i in range(25, 29):
            short = [c for c in res.candidates if abs(c.x - truth[i][0]) <= 3 and abs(c.y - truth[i][1]) <= 3]
            assert short and all(14.0 <= c.length < 20.0 for c in short)
            d = res.detection
            hits.append(d is not None and math.hypot(d.x - truth[i][0], d.y - truth[i][1]) <= 3)
            far = [c for c in res.candidates if math.hypot(c.x - 301, c.y - 501) <= 3]
            assert far and all(c.rejected_by == "length" for c in far)
    assert all(hits) if guided is None else not any(hits)


def _player_leaves(n=70, stand=range(10, 25)):
    """A bright court (grey 150) where a dark player (a 40 × 80 px block, grey 40) stands for
    half a second (``stand``), then is gone: the court he uncovers is brighter than an average
    that learnt him. Grey frames at 1280 × 720 (the broadcast preset's processing scale is 1)."""
    rng = np.random.default_rng(5)
    frames = []
    for i in range(n):
        img = np.clip(rng.normal(150, 2, (720, 1280)), 0, 255).astype(np.uint8)
        if i in stand:
            img[300:380, 600:640] = 40
        frames.append(img)
    return frames


@pytest.mark.parametrize("dark", [0, 30])
def test_a_dark_player_who_leaves_leaves_no_bright_ghost(dark):
    """With background.dark_threshold the pixels darker than the average learn slowly (like the
    foreground), so the running average never learns the player and the court he uncovers is
    not foreground; without it (the default) it floods the mask where he stood."""
    from badminton_gui.core.background import BackgroundModel
    p = load_preset("broadcast").with_value("background.dark_threshold", dark)
    model = BackgroundModel(p.background, p.binarize)
    ghost = []
    for i, img in enumerate(_player_leaves()):
        mask = model.apply(img)
        if i >= 25:
            ghost.append(np.count_nonzero(mask[300:380, 600:640]) / (80 * 40))
    if dark:
        assert max(ghost) < 0.05
    else:
        # the 45 frames after he left: still most of the patch
        assert min(ghost) > 0.5


def test_dark_threshold_is_off_by_default_and_on_in_the_broadcast_preset():
    assert TrackerParams().background.dark_threshold == 0
    assert load_preset("default").background.dark_threshold == 0
    assert load_preset("broadcast").background.dark_threshold == 30


def _clear_out_of_the_top(n=75, out=range(20, 50), flicker=None):
    """A TV-sized flight (1280×720 at 30 fps): the shuttle (a 3 px dot) rises 30 px a frame and
    leaves through the top edge after frame 19, is out of the picture in the ``out`` frames and
    comes back down through the top edge; meanwhile a second, dimmer dot (a player's shoe, say)
    crawls across the court at 6 px a frame. Returns the frames and the shuttle's position per
    frame (None while out). ``flicker`` = (frame, (x, y)): one more dot in that frame only."""
    rng = np.random.default_rng(7)
    frames, truth = [], []
    for i in range(n):
        img = np.clip(rng.normal(60, 2, (720, 1280, 3)), 0, 255).astype(np.uint8)
        cv2.circle(img, (100 + 6 * i, 500), 3, (150, 150, 150), -1)
        if i < out.start:
            pos = (640, 590 - 30 * i)
        elif i >= out.stop:
            pos = (700, 5 + 20 * (i - out.stop))
        else:
            pos = None
        if pos is not None:
            cv2.circle(img, pos, 3, (240, 240, 240), -1)
        if flicker is not None and i == flicker[0]:
            cv2.circle(img, flicker[1], 3, (240, 240, 240), -1)
        frames.append(img)
        truth.append(pos)
    return frames, truth


@pytest.mark.parametrize("margin", [0.0, None])
def test_nothing_is_reported_while_the_shuttle_is_out_of_the_picture(margin):
    """The broadcast preset's ``association.exit_margin``: a shuttle-like track that leaves
    through the edge it moves towards (a clear above the TV picture) is out of sight; whatever
    else the association offers meanwhile is not the shuttle, until a new track comes in from
    an edge. Off (``margin=0``, the preset before) the crawling dot takes the report."""
    p = load_preset("broadcast")
    assert p.association.exit_margin == 40.0
    # The hand-made quality (contrast and size: the dimmer dot scores lower), not the TV
    # classifier, whose scores of synthetic dots mean nothing.
    p = p.with_value("classifier.enabled", False)
    if margin is not None:
        p = p.with_value("association.exit_margin", margin)
    frames, truth = _clear_out_of_the_top()
    det = CameraDetector(p)
    reported_out, back = [], []
    for i, img in enumerate(frames):
        d = det.process(img, i / FPS, keep_mask=False).detection
        if i in range(16, 20):
            assert d is not None and math.hypot(d.x - truth[i][0], d.y - truth[i][1]) <= 5
        if 22 <= i < 50:
            reported_out.append(d is not None)
        if i >= 55:
            back.append(d is not None and math.hypot(d.x - truth[i][0], d.y - truth[i][1]) <= 5)
    if margin is None:
        assert not any(reported_out)
        assert all(back)
    else:
        assert all(reported_out)   # the crawling dot, while the shuttle is out
        assert not any(back)       # ... and after: it keeps the lead it took


def test_the_hold_ends_when_a_young_track_takes_the_returning_shuttle():
    """A flicker (one frame, well inside the picture) starts a track just before the shuttle
    comes back; the track's velocity is unknown, its gate wide, and it takes the shuttle's first
    blob at the top edge. That track has now been at the edge: the shuttle is back and reported
    (it used to be held back, like everything else, until the timeout, because the track's
    first point was the flicker's: 1_02_01 111 with filter 1 at 18 px lost 80 frames)."""
    p = load_preset("broadcast").with_value("classifier.enabled", False)
    frames, truth = _clear_out_of_the_top(flicker=(49, (850, 150)))
    det = CameraDetector(p)
    tracks = {}
    for i, img in enumerate(frames[:51]):
        result = det.process(img, i / FPS, keep_mask=False)
        for frame, (x, y) in ((49, (850, 150)), (50, truth[50])):
            if i == frame:
                tracks[frame] = [c.tracklet for c in result.candidates if math.hypot(c.x - x, c.y - y) <= 5]
        if i in range(22, 50):
            assert result.detection is None                       # held while the shuttle is out
    assert tracks[49] == tracks[50] and len(tracks[50]) == 1   # the flicker's track took it
    d = result.detection
    assert d is not None and math.hypot(d.x - truth[50][0], d.y - truth[50][1]) <= 5


def test_an_old_track_comes_in_only_by_the_points_it_gained_since_the_exit():
    """``came_in``, the exit hold's test of a returning track: an old clutter track can take the
    returning shuttle's blob
    into its gate (bwf_00001 90 with the gate slack at 30 px: a track that had sat at (733, 317)
    took the shuttle at the top edge and everything stayed held for 40 frames). Its points
    before the exit say nothing; those since do."""
    from badminton_gui.core.association import Tracklet
    from badminton_gui.core.detect.tracklets import came_in

    def track(ident, points, hits):
        tr = Tracklet(ident, *points[-1], 0.0, *points[0], hits=hits)
        tr.recent.extend(points)
        return tr

    w, h, entry, first = 1280, 720, 120.0, 50
    sat = [(733.0, 317.0)] * 5
    # An old track (ident 24 < first) with 5 hits at the exit, 2 more since: the shuttle's.
    old = track(24, sat + [(736.0, 13.0), (737.0, 29.0)], hits=7)
    assert came_in(old, first, {24: 5}, w, h, entry)
    # The same track without new points near an edge: still held.
    assert not came_in(track(24, sat + [(735.0, 320.0)], hits=6), first, {24: 5}, w, h, entry)
    # Its edge points from before the exit do not count (it was the shuttle leaving).
    leaving = track(24, [(736.0, 13.0)] + sat, hits=6)
    assert not came_in(leaving, first, {24: 5}, w, h, entry)
    # A track born after the exit: any of its points.
    young = track(60, [(992.0, 173.0), (847.0, 6.0), (847.0, 17.0)], hits=3)
    assert came_in(young, first, {}, w, h, entry)


def test_another_track_leaving_through_the_top_does_not_hold_the_followed_shuttle():
    """The followed shuttle flies across the picture while another shuttle-like dot (a second
    shuttle, a bright clutter track) rises out through the top edge: the shuttle being
    followed is still in the picture, so nothing is held back (bwf_00001 242 with the speed
    gate gain at 0.75: the shuttle was held back for 3 s)."""
    p = load_preset("broadcast").with_value("classifier.enabled", False)
    rng = np.random.default_rng(5)
    det = CameraDetector(p)
    on_shuttle = []
    for i in range(45):
        img = np.clip(rng.normal(60, 2, (720, 1280, 3)), 0, 255).astype(np.uint8)
        shuttle = (100 + 20 * i, 400)
        cv2.circle(img, shuttle, 3, (240, 240, 240), -1)
        if 6 <= i < 20:
            cv2.circle(img, (1000, 300 - 25 * (i - 6)), 3, (240, 240, 240), -1)   # gone after 17
        d = det.process(img, i / FPS, keep_mask=False).detection
        if i >= 5:
            on_shuttle.append(d is not None and math.hypot(d.x - shuttle[0], d.y - shuttle[1]) <= 5)
    assert all(on_shuttle), [i + 5 for i, ok in enumerate(on_shuttle) if not ok]


def test_the_shuttle_out_of_the_picture_is_given_up_after_the_timeout():
    """A shuttle that never comes back (a new one brought into play off screen): after
    ``exit_timeout`` the association reports again."""
    p = (load_preset("broadcast").with_value("association.exit_timeout", 0.5)
         .with_value("classifier.enabled", False))
    frames, _ = _clear_out_of_the_top(n=50, out=range(20, 60))
    det = CameraDetector(p)
    reported = [det.process(img, i / FPS, keep_mask=False).detection is not None
                for i, img in enumerate(frames)]
    assert not any(reported[22:34]) and all(reported[40:])


def test_exit_margin_is_off_by_default():
    assert TrackerParams().association.exit_margin == 0.0
    assert load_preset("default").association.exit_margin == 0.0
    assert load_preset("coarse").association.exit_margin == 0.0


def test_only_the_top_edge_is_an_exit():
    """A shuttle-like dot leaving through the bottom edge (a racket, a near player's hand on
    TV) does not stop the reports: players and rackets cross the side and bottom edges."""
    p = load_preset("broadcast").with_value("classifier.enabled", False)
    frames, _ = _clear_out_of_the_top()
    frames = [np.ascontiguousarray(img[::-1]) for img in frames]   # out through the bottom
    det = CameraDetector(p)
    reported = [det.process(img, i / FPS, keep_mask=False).detection is not None
                for i, img in enumerate(frames)]
    assert all(reported[22:50])


SERVE_CLIP = DATA / "bwf_00001.mp4"   # tuned-on; frames 0–15: the serve, the shuttle held still


def _held_serve_reports(lone_quality: float) -> dict[int, float]:
    """Frames 0–8 of bwf_00001 with the broadcast preset and a classifier sure of the held
    shuttle: {frame: distance of the report from the labelled shuttle (inf: nothing reported)}.
    The candidates are scored from the labels (0.9 at the label, 0.01 elsewhere) so that the test
    pins the rule, not a classifier: the TV classifier trained on all five venues scores this
    held shuttle 0.2–0.4 (frames 3–7), below the preset's 0.75, and leaves it to the look-ahead's
    lead-in."""
    labels = read_point_labels(SERVE_CLIP.with_name("bwf_00001_ball.csv")).as_dict()
    det = CameraDetector(load_preset("broadcast").with_value("association.lone_quality", lone_quality))
    tol = tolerance_px(1280)
    label = [0.0, 0.0]
    det.use_classifier(None)
    det.use_score(lambda xs, ys, *_: np.where(np.hypot(xs - label[0], ys - label[1]) <= tol, 0.9, 0.01))
    cap = cv2.VideoCapture(str(SERVE_CLIP))
    out = {}
    for i in range(9):
        ok, frame = cap.read()
        assert ok
        _, label[0], label[1] = labels[i]
        d = det.process(frame, i / 30.0, keep_mask=False).detection
        _, lx, ly = labels[i]
        out[i] = math.hypot(d.x - lx, d.y - ly) if d is not None else math.inf
    cap.release()
    return out


@pytest.mark.skipif(not SERVE_CLIP.is_file(), reason="real data (../shared/data) not available")
def test_the_held_serve_is_reported_when_nothing_travels():
    """The server holds the shuttle still (labelled visible on TV): no tracklet travels, so the
    association refuses it; ``lone_quality`` reports the blob the classifier is sure of (here a
    classifier sure of the label: ``_held_serve_reports``)."""
    tol = tolerance_px(1280)
    off = _held_serve_reports(1.0)
    assert all(v == math.inf for v in off.values())          # the old rule: nothing
    on = _held_serve_reports(load_preset("broadcast").association.lone_quality)
    assert sum(v <= tol for v in on.values()) >= 5, on        # frames 3–7 (0–2: no mask yet)
    assert all(v <= tol or v == math.inf for v in on.values()), on


def test_lone_quality_only_in_the_broadcast_preset():
    """Off on the two-camera rig: its labels do not mark the still shuttle the way TV labels
    do (on the tuned-on rallies at 0.75: 98.00 → 96.48 %, 217 more FP2)."""
    assert TrackerParams().association.lone_quality == 1.0
    assert load_preset("default").association.lone_quality == 1.0
    assert load_preset("coarse").association.lone_quality == 1.0
    assert load_preset("broadcast").association.lone_quality == 0.75
