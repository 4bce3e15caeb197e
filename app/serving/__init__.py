"""Serving the app: the viser server, the classroom, the gate on its websocket, the workers, logs and metrics.

Nothing here teaches: it builds each browser's session (:mod:`ur10teach.session`), shares
the presenter's arm with a class, keeps one client from stalling the others, and reports.
"""
