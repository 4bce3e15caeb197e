"""Every tolerance of the core, in one place (the compiled kernel is handed these values).

The IK's decisions follow the conditioning of the numbers they are made from
(docs/kinematics.md §4.3): a choice along a direction the pose barely fixes is allowed
exactly as far as it keeps the pose within these bounds.
"""

from __future__ import annotations

import math

#: Metres. A frame-4 origin this far beyond the elbow's reach (or a wrist-2 point this far
#: inside the shoulder cylinder) is put on the boundary, not refused; the pose then moves
#: by at most this much.
LENGTH_TOLERANCE = 1e-9

#: Metres. Where the pose fixes a value only loosely, the IK may choose it — keep the
#: hint's, or pick one that reaches — as long as the choice moves the arm by at most this
#: much. Near the shoulder singularity the signed reach A of the wrist-2 point is
#: uncertain (ρ² − d4² cancels: ~1e-8 m at A = 0): any A of the band that moves P5 by at
#: most this much (±0.6 µm at A = 0) will do, and θ1 with it. At the stretched or folded
#: elbow θ3 = ±acos(c3) is fixed only to √rounding: the hint's θ3 is kept where it puts
#: the frame-4 origin within this much of where the pose puts it.
CHOICE_TOLERANCE = 1e-12

#: Metres. How far beyond the elbow's exact reach rounding alone puts the frame-4 origin of
#: a reachable pose (a few ulp of metre-sized lengths). Only a slot beyond this looks for
#: another choice that reaches (another A, θ6 or θ1): such a search can turn the wrist's
#: split of θ234 ± θ6 by up to π at a triple singularity, and lose the hint's branch, to
#: save a clamp of c3 that moves the pose by less than this.
REACH_ROUNDING = 1e-14

#: Not a tolerance but a bound that saves work: moving the reach A within its band moves
#: the elbow's distance r by at most about this many times as much (more only near the
#: wrist singularity, where θ1 is turned instead), so a band this many times narrower than
#: the distance r must go is not tried.
BAND_LEVERAGE = 1000.0

#: How much a choice along the wrist's singular direction may change the rotation.
#: Turning θ6 by Δ and θ2 + θ3 + θ4 by ∓Δ (so that θ234 ± θ6 stays) changes every entry
#: of R06 by about |s5|·|Δ| at most (1.4 |s5| |Δ| measured over all θ5, |s5| |Δ| near
#: s5 = 0); that estimate must stay below this value.
WRIST_TURN_TOLERANCE = 1e-10

#: |s5| below which every θ6 qualifies (WRIST_TURN_TOLERANCE / π): the wrist is singular,
#: axes 4 and 6 parallel, and θ6 is chosen rather than computed.
WRIST_TOLERANCE = WRIST_TURN_TOLERANCE / math.pi

#: The spherical-wrist arms (:mod:`ur10core.solvers.spherical_wrist`): a hint this close to
#: the line between two branches counts as on both sides of it, so that where the branches
#: meet the hint's value is kept for either (the sine of the hint's elbow angle β of an
#: articulated arm; the hint's reach along the Stanford arm's boom, in metres).
SIDE_TOLERANCE = 1e-6

#: |sin β| at most this: an articulated arm's elbow is stretched or folded, β fixed only to
#: √rounding, and the slot is flagged singular.
STRETCHED_TOLERANCE = 1e-9

#: Metres or radians. A joint value this far beyond a limit is at the limit: IK at a pose on a
#: limit (the desktop arm's forearm level, θ3 = 0) gives it to rounding, either side of it,
#: and a slider's value is compared to it as closely. On a stretched or folded elbow the
#: elbow's angle, and the joints that follow from it, are fixed only to √rounding (3e-8 rad
#: measured on the KR210, with θ2 and θ5 on their limits): a few times that.
LIMIT_TOLERANCE = 1e-7

#: A squared length's relative rounding, a few ulp: where the IK takes the difference of two squares, the
#: difference is known only to this times the larger. The Stanford arm's reach u, from u² = ρ² − d2², is then
#: known to about SQUARE_ROUNDING ρ² / |u|, and θ2 = atan2(u, z) to that over the stroke. A slot whose θ2 is fixed
#: less well than LIMIT_TOLERANCE is flagged singular; where it came out just beyond a limit, it is put on it
#: (:func:`ur10core.solvers.numerical.settle_on_limits`). A spherical wrist's rotation W (a product of rotations) has
#: entries known to about this much too, so θ4 = atan2(W23, W13) to this over sin θ5: a slot whose θ4 is fixed less
#: well than LIMIT_TOLERANCE (θ5 within about 9e-9 rad of 0) is flagged singular likewise.
SQUARE_ROUNDING = 4 * 2.0**-52

#: A pose's rotation part may deviate from orthonormal by this much (max |Rᵀ R − I|).
ROTATION_TOLERANCE = 1e-6

#: A pose's bottom row must equal [0, 0, 0, 1] to this tolerance.
BOTTOM_ROW_TOLERANCE = 1e-9

#: Below this cos β the Z-Y-X angles are at gimbal lock (β = ±90°): α is set to 0; below this
#: sin θ the Z-Y-Z angles are (θ = 0 or π): φ is set to 0 (:mod:`ur10core.orientation`).
GIMBAL_TOLERANCE = 1e-10

#: Squared joint distances (rad²) closer than this count as a tie when the nearest branch
#: is chosen (:func:`ur10core.ik.nearest_branch`).
TIE_TOLERANCE = 1e-10
#: A body this far below z = 0 is through the floor (m): the base's own underside sits on it.
FLOOR_TOLERANCE = 1e-3
