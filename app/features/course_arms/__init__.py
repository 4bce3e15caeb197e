"""The course's other arms in the app: pick one, drive it, see its branches, singularities and DH frames.

One browser drives one :class:`ur10core.Arm` drawn from its DH table (``session.CourseArmSession``):
its state (``state``), what is drawn in 3D (``scene``: the DH skeleton, its frames, the
ghost branches) and the panel (``panel``: sliders, branch table, singularity factors,
the DH table in both conventions); the features every arm shares come from ``ur10teach.features``.
The UR10 keeps its own session for its meshes, eight ghosts and overlay (``ur10teach.session``);
``ur10teach.features.arm_picker`` switches a browser between them.
"""
