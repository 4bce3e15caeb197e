"""The teaching features: one module each, each working for any arm where its maths applies.

A feature is a view (:class:`ur10teach.view.View`): it builds its folder in the panel and
its nodes in the 3D scene, and draws from the arm's snapshots (``render`` with the arm,
``render_panel`` at most ten times a second). Where a colour or a label is set: the module
of the feature, and :mod:`ur10teach.style`.
"""
