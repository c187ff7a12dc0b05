"""The calibration stage: from chessboard views to a rig file, and refining a rig afterwards.

``board`` (the target, detecting it in one image, per-view checks) → ``coverage`` (how much of
the pose space the captured views span) → ``folders`` (two image folders → stereo views) →
``stereo`` (the solve, its figures, the rectified preview) → ``court_pose`` (the rig in the
court frame from clicked points). ``refine`` refits a rig's relative pose from the shuttle's
own pairs after a rally (self-calibration).
"""
