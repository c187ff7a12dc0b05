"""The per-camera detection stages, in the order a frame goes through them.

``segmentation`` (background model → foreground mask and contours) → ``candidates`` (contours →
filters 1 and 2: contour length, shortest side of the tilted rectangle; the blobs worth a
closer look) → ``measure`` (each blob's full-resolution window: filter 3, whiteness, and the
appearance features) → ``scoring`` (how shuttle-like each blob looks) → ``tracklets`` (filter
4, motion: the blobs joined into image tracklets, and what the detector reports from them).
``core/detector.py`` runs them in that order for one camera (``CameraDetector``).
"""
