"""The operator's desktop application (PySide6 + pyqtgraph); the only layer that imports Qt.

Why this package exists: it renders what the core computes. ``app.main`` is the
``badminton-gui`` entry point; ``worker`` runs the source and the tracker off the GUI thread;
everything else is widgets that only draw frozen results.
"""
