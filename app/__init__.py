"""The browser teaching app: a viser server that shows the UR10 and its kinematics.

Every number it shows comes from :mod:`ur10core`; this package only wires the scene
and the GUI. One module per feature:

* ``joint_panel``  — the six joint sliders, pose buttons, typed joint vectors
* ``readouts``     — T06 and the four orientation readouts
* ``ik_target``    — the draggable target, the eight ghost arms, the branch list
* ``singularity``  — the singularity-manifold overlay (gauges, plot, geometry, demos)
* ``workspace``    — the workspace point cloud
* ``floor``        — red discs under an arm or ghost that reaches below the floor
* ``robot``        — the solid arm built from the link meshes
* ``camera``       — framing the arm beside the docked panel, the "View" folder
* ``lecture``      — lecture mode: big type, thick lines, the panel folded away
* ``state``        — what one arm is doing (no viser: unit-tested on its own)
* ``session``      — one browser's arm, panel and target
* ``session_basics`` — what every arm's session does alike (batched redraws, the panel, leaving)
* ``classroom``    — shared demo mode: the presenter, viewers, explorers
* ``shared_frames`` — a shared redraw encoded once for every browser
* ``server``       — the viser server, clients coming and going
"""
