"""One camera's detector in a process of its own, and its stand-in in the tracker's process.

Why this file exists: a camera's stages 1–4 (``CameraDetector``) are mostly small Python and
OpenCV calls that hold the GIL, so two camera threads in one process mostly take turns. In a
process each (``StereoTracker(..., processes=True)``, ``core/execution.py``) the two cameras'
candidates are found at the same time, while the stereo stage stays in the tracker's process.

The stereo stage asks a camera's detector about its candidates during a step and tells it what
it decided. :class:`RemoteDetector` stands in for the detector there:

- the frame goes to the worker through shared memory, with the frame's time and ``keep_whole``:
  copied into one buffer per camera (the tracker writes the next frame only once it has the
  last one's result, and the detector keeps no reference to a frame after it), or, when the
  frame was put in one of the stand-in's ``frame_buffer`` ring (a decoder writing there), not
  copied at all;
- the worker runs ``plan_window`` and ``find_candidates`` on it and sends back the
  ``CameraResult`` with a :class:`~badminton_gui.core.detect.answers.DetectorSnapshot`; the
  questions about the tracklets behind the candidates are answered from it, by the same code
  the detector answers them with (``TrackletQueries``);
- what the stereo stage tells the detector (``commit``, ``protect_report``, new parameters,
  ``reset``, ...) is queued and sent ahead of the next message, in order, so the worker's
  detector sees the same calls in the same order as one in the tracker's process;
- the rare questions that need the frame's mask or background (``is_blind``, ``is_merged``: the
  flight's coast for a camera without a detection) are asked of the worker, which waits for
  messages between frames.

Spawn-safe: the worker's entry point is a module-level function and everything it gets is
picklable, so it runs under the ``spawn`` start method (the default here: safe beside threads,
the GUI's among them).
"""

from __future__ import annotations

import multiprocessing as mp
import time
import traceback
from multiprocessing import shared_memory

import cv2
import numpy as np

from .detect.answers import DetectorSnapshot, SnapshotTracklets, TrackletQueries
from .params import TrackerParams
from .types import CameraResult, Candidate

# Frame buffers in a ring (``RemoteDetector.frame_buffer``): a frame is read again on the
# tracker's next step (its motion check), so a buffer is refilled two frames later at the soonest.
SLOTS = 3
# What the stereo side may tell the worker's detector: the detector's methods, called in order.
_FEEDBACK = frozenset({"commit", "protect_report", "set_params", "reset", "set_window_phase",
                       "use_rig", "use_classifier", "use_score"})
# What it may ask the worker and wait for (names of the detector's methods or attributes).
_QUESTIONS = frozenset({"is_blind", "is_merged", "classifier", "model_scale"})


class CameraProcessError(RuntimeError):
    """The camera's worker process failed (its traceback is the message)."""


def serve(conn, params: TrackerParams, geometry) -> None:
    """The worker: one ``CameraDetector`` answering the messages of a :class:`RemoteDetector`.

    Each message is (feedback calls, request); a request is ("frame", buffer name, shape, dtype,
    t, keep_mask, keep_whole), ("ask", name, args or None) or ("close",). Every request but
    "close" is answered ("ok", value) or ("error", traceback)."""
    from .detector import CameraDetector

    cv2.setNumThreads(1)          # one core per camera process
    detector = CameraDetector(params, geometry)
    buffers: dict[str, shared_memory.SharedMemory] = {}
    try:
        while True:
            try:
                ops, request = conn.recv()
            except EOFError:
                return
            if request[0] == "close":
                return
            try:
                for name, args in ops:
                    getattr(detector, name)(*args)
                if request[0] == "frame":
                    _, buf_name, shape, dtype, t, keep_mask, keep_whole = request
                    if buf_name not in buffers:
                        if len(buffers) > SLOTS:       # the tracker's buffers were replaced
                            for old in buffers.values():
                                old.close()
                            buffers = {}
                        # The tracker's process alone unlinks it (the resource tracker is shared).
                        buffers[buf_name] = shared_memory.SharedMemory(name=buf_name)
                    frame = np.ndarray(shape, dtype, buffer=buffers[buf_name].buf)
                    detector.keep_whole = keep_whole
                    detector.plan_window(frame, t)
                    result = detector.find_candidates(frame, t, keep_mask)
                    del frame
                    reply = ("ok", (result, detector.snapshot(result), time.thread_time()))
                else:
                    _, name, args = request
                    value = getattr(detector, name)
                    reply = ("ok", value if args is None else value(*args))
            except Exception:   # noqa: BLE001  the tracker's process raises it
                reply = ("error", traceback.format_exc())
            conn.send(reply)
    finally:
        for shm in buffers.values():
            shm.close()


def _free(shm: shared_memory.SharedMemory | None) -> None:
    """Unlink a frame buffer of ours; its mapping goes once no array of it is left (the
    tracker may still hold its last frame)."""
    if shm is None:
        return
    try:
        shm.close()
    except BufferError:
        pass
    shm.unlink()


class RemoteDetector(TrackletQueries):
    """A ``CameraDetector`` running in a worker process, as the stereo tracker uses one.

    ``submit`` a frame, then ``collect`` its ``CameraResult`` (``find_candidates`` does both);
    ask and tell it what the tracker asks and tells a ``CameraDetector``. ``worker_cpu``: the
    worker's CPU seconds so far (as of its last frame); ``copy_cpu``: this process's spent
    copying the frames into shared memory. ``close`` ends the worker."""

    def __init__(self, params: TrackerParams | None = None, geometry=None, start_method: str = "spawn") -> None:
        self.params = params or TrackerParams()
        ctx = mp.get_context(start_method)
        self._conn, theirs = ctx.Pipe()
        self._proc = ctx.Process(target=serve, args=(theirs, self.params, geometry), daemon=True,
                                 name="camera-detector")
        self._proc.start()
        theirs.close()
        self._pending: list[tuple[str, tuple]] = []
        self._associator = SnapshotTracklets()
        self._shm: shared_memory.SharedMemory | None = None
        self._ring: list[tuple[shared_memory.SharedMemory, int]] = []   # (buffer, its address)
        self._turn = 0
        self._awaiting = False
        self.keep_whole = False
        self.last_diagnostics = None
        self.last_scored: tuple[np.ndarray, np.ndarray] = (np.zeros((0, 2)), np.zeros((0, 0)))
        self.worker_cpu = 0.0
        self.copy_cpu = 0.0      # this process's CPU seconds spent copying frames to the worker
        self.questions = 0       # questions asked of the worker and waited for (``is_blind``, ...)

    @property
    def _looks(self) -> SnapshotTracklets:
        return self._associator

    # ---- one frame -------------------------------------------------------------------------
    def plan_window(self, frame_bgr: np.ndarray, t: float) -> bool:
        """The worker plans the frame's window itself, just before its candidates."""
        return False

    def submit(self, frame_bgr: np.ndarray, t: float, keep_mask: bool = True) -> None:
        """Send the frame to the worker (it starts on it at once); ``collect`` takes the result."""
        if self._awaiting:
            raise RuntimeError("collect the last frame's result before submitting another")
        frame = np.ascontiguousarray(frame_bgr)
        shm = self._ring_buffer_of(frame)
        if shm is None:
            if self._shm is None or self._shm.size < frame.nbytes:
                _free(self._shm)
                self._shm = shared_memory.SharedMemory(create=True, size=max(frame.nbytes, 1))
            shm = self._shm
            c0 = time.thread_time()
            np.copyto(np.ndarray(frame.shape, frame.dtype, buffer=shm.buf), frame)
            self.copy_cpu += time.thread_time() - c0
        self._send(("frame", shm.name, frame.shape, frame.dtype.str, float(t), bool(keep_mask),
                    bool(self.keep_whole)))
        self._awaiting = True

    def frame_buffer(self, shape: tuple[int, ...], dtype=np.uint8) -> np.ndarray:
        """An array in shared memory to put the next frame in (a decoder may write it there):
        ``submit`` of it hands the worker its name, no copy. The buffers are taken in turn from a
        ring of ``SLOTS``; one stays as filled until ``SLOTS - 1`` more are taken, so take one per
        frame and process that frame before taking the next."""
        nbytes = max(int(np.prod(shape)) * np.dtype(dtype).itemsize, 1)
        if not self._ring or self._ring[0][0].size < nbytes:
            for shm, _ in self._ring:
                _free(shm)
            self._ring = []
            for _ in range(SLOTS):
                shm = shared_memory.SharedMemory(create=True, size=nbytes)
                self._ring.append((shm, np.frombuffer(shm.buf, np.uint8, count=1).__array_interface__["data"][0]))
        shm = self._ring[self._turn][0]
        self._turn = (self._turn + 1) % SLOTS
        return np.ndarray(shape, dtype, buffer=shm.buf)

    def _ring_buffer_of(self, frame: np.ndarray) -> shared_memory.SharedMemory | None:
        """The ring buffer ``frame`` fills from its start (``frame_buffer``), or None."""
        at = frame.__array_interface__["data"][0]
        for shm, address in self._ring:
            if at == address and frame.nbytes <= shm.size:
                return shm
        return None

    def collect(self) -> CameraResult:
        """The submitted frame's candidates (filters 1–4 applied, no choice made yet)."""
        self._awaiting = False
        result, snapshot, cpu = self._reply()
        self._install(snapshot)
        self.worker_cpu = cpu
        return result

    def find_candidates(self, frame_bgr: np.ndarray, t: float, keep_mask: bool = True) -> CameraResult:
        self.submit(frame_bgr, t, keep_mask)
        return self.collect()

    def _install(self, snapshot: DetectorSnapshot) -> None:
        self._associator = SnapshotTracklets(snapshot)
        self.last_diagnostics = snapshot.diagnostics
        if snapshot.scored is not None:
            self.last_scored = snapshot.scored

    # ---- what the stereo stage tells the detector ------------------------------------------
    def commit(self, detection: Candidate | None, t: float, candidates: tuple[Candidate, ...] = ()) -> None:
        """Follow the chosen candidate's tracklet (the snapshot's answers follow it at once)."""
        if detection is None:
            return
        self._associator.select(detection.tracklet if detection.tracklet >= 0 else None)
        self._tell("commit", detection, t)

    def protect_report(self, report: Candidate | None, width: int) -> None:
        self._tell("protect_report", report, width)

    def set_params(self, params: TrackerParams) -> None:
        self.params = params
        self._tell("set_params", params)

    def reset(self) -> None:
        self._associator = SnapshotTracklets()
        self._tell("reset")

    def set_window_phase(self, phase: float) -> None:
        self._tell("set_window_phase", float(phase))

    def use_rig(self, rig, camera: int) -> None:
        self._tell("use_rig", rig, int(camera))

    def use_classifier(self, classifier) -> None:
        self._tell("use_classifier", classifier)

    def use_score(self, score) -> None:
        """``score`` must be picklable (a module-level function): it runs in the worker."""
        self._tell("use_score", score)

    def _tell(self, name: str, *args) -> None:
        assert name in _FEEDBACK
        self._pending.append((name, args))

    # ---- what it asks the worker -----------------------------------------------------------
    def is_blind(self, x: float, y: float) -> bool:
        return self._ask("is_blind", float(x), float(y))

    def is_merged(self, x: float, y: float) -> bool:
        return self._ask("is_merged", float(x), float(y))

    def model_scale(self, width: int, height: int) -> float:
        return self._ask("model_scale", int(width), int(height))

    @property
    def classifier(self):
        """A copy of the worker's classifier (None: the hand-made score)."""
        return self._ask_attribute("classifier")

    def _ask(self, name: str, *args):
        assert name in _QUESTIONS
        self.questions += 1
        self._send(("ask", name, args))
        return self._reply()

    def _ask_attribute(self, name: str):
        assert name in _QUESTIONS
        self._send(("ask", name, None))
        return self._reply()

    # ---- the pipe --------------------------------------------------------------------------
    def _send(self, request: tuple) -> None:
        if self._awaiting:
            raise RuntimeError("the worker is on a frame: collect its result first")
        ops, self._pending = self._pending, []
        self._conn.send((ops, request))

    def _reply(self):
        try:
            status, value = self._conn.recv()
        except (EOFError, OSError):
            # Under ``spawn`` a script that starts a tracker outside ``if __name__ == "__main__":``
            # starts it again in the worker, which then fails on its import.
            self._proc.join(timeout=1)
            raise CameraProcessError(f"the camera's worker process ended (exit code {self._proc.exitcode})") from None
        if status == "error":
            raise CameraProcessError(value)
        return value

    def close(self) -> None:
        """End the worker (waits for it) and free the frame buffer."""
        if self._proc is not None:
            try:
                if self._awaiting:
                    self._conn.recv()
                self._conn.send(([], ("close",)))
            except (OSError, EOFError):
                pass
            self._proc.join(timeout=10)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join()
            self._conn.close()
            self._proc = None
        for shm in [self._shm] + [shm for shm, _ in self._ring]:
            _free(shm)
        self._shm, self._ring = None, []

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:   # noqa: BLE001  interpreter shutdown
            pass
