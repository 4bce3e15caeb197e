"""The browser teaching app: a viser server that shows the course's arms and their kinematics.

Every number it shows comes from :mod:`ur10core`; this package only wires the scene and
the GUI. Its folders:

* ``features/``        — the teaching features, one module each, for every arm where its maths applies
* ``serving/``         — the server, the classroom, the gate, the workers, logs and metrics
* ``viser_internals/`` — the only code that touches viser's internals

and, beside them: ``session`` (one browser's arm, panel and target, for any arm), ``state`` (what one arm is doing: no viser, unit-tested on its
own), ``view``, ``style``, ``feedback`` and ``meshes``.
"""
