/*
 * ur10core's compiled kernel: the UR family's eight-slot IK, the closed-form FK, the DH
 * frames, quaternions and the nearest-branch pick, and the spherical-wrist arms' IK, in C.
 *
 * An accelerator, not a second method: every function follows its Python counterpart
 * step for step (the IK: ur10core/ik_reference.py; the other arms' IK: _solve_one in
 * ur10core/solvers/spherical_wrist.py; the rest: ur10core/_numpy_kernels.py),
 * with the same formulas in the same order, and the tests compare the two backends,
 * flags, failure codes and distances included. ur10core runs without it
 * (UR10CORE_BACKEND=numpy, or no C compiler at install time).
 *
 * Portable C99 that MSVC also compiles: no M_PI, no variable-length arrays.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846
#define TAU (2.0 * PI)

/* ur10core/tolerances.py, handed over by set_tolerances() when ur10core loads this module. */
static int configured = 0;
static double LENGTH_TOLERANCE, CHOICE_TOLERANCE, WRIST_TURN_TOLERANCE, WRIST_TOLERANCE, ROTATION_TOLERANCE,
    BOTTOM_ROW_TOLERANCE, BAND_LEVERAGE, REACH_ROUNDING, SIDE_TOLERANCE, STRETCHED_TOLERANCE, LIMIT_TOLERANCE,
    SQUARE_ROUNDING;

enum { REACHABLE = 0, WRIST_INSIDE_CYLINDER = 1, ELBOW_TOO_FAR = 2, ELBOW_TOO_CLOSE = 3 };
/* ur10core/branches.py's failure codes, for the other arms */
enum { INSIDE_OFFSET_CODE = 1, TOO_FAR_CODE = 2, TOO_CLOSE_CODE = 3 };

typedef struct {
    double d1, a2, a3, d4, d5, d6;
} Params;

typedef struct {          /* where one pose's results go */
    double *q;            /* 48: slot-major, 6 joints per slot */
    npy_bool *valid;      /* 8 */
    npy_bool *wrist;      /* 8 */
    npy_bool *elbow;      /* 8 */
    npy_int8 *failure;    /* 8 */
    double *elbow_distance; /* 8 */
    double *rho;          /* 1 */
    npy_bool *shoulder;   /* 1 */
} Out;

typedef struct {          /* a pose's rotation and wrist-2 point */
    double r11, r12, r13, r21, r22, r23, r31, r32, r33;
    double p5x, p5y, p5z;
} Pose;

typedef struct {          /* one (theta1, wrist sign) pair: ik_reference._wrist_and_elbow's tuple */
    double theta1, theta5, theta6, theta234, s5_abs, h4, v4, r;
} Slot;

typedef struct {          /* what both wrist signs of one theta1 share: steps 1 and 2 */
    double c1, s1, A, theta1, c5, c6s5, s6s5, s5_abs, theta5; /* theta5 of the wrist not flipped */
} Shoulder;

/* Into (-pi, pi], exactly (IEEE remainder), in O(1) for any finite angle: ik_reference.wrap. */
static double wrap(double angle)
{
    if (angle > -PI && angle <= PI) return angle; /* most are: what remainder() would return */
    /* one turn out, as a sum or a difference of two angles is: one exact step (Sterbenz), remainder()'s result */
    if (angle > PI && angle < 2.5 * PI) return angle - TAU;
    if (angle <= -PI && angle > -2.5 * PI) return angle + TAU;
    angle = remainder(angle, TAU);
    return angle <= -PI ? angle + TAU : angle;
}

static double clamp_unit(double x)
{
    return x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x);
}

/* 1 if T (row-major 4x4) is finite, has bottom row [0 0 0 1] and a proper rotation part. */
static int pose_is_valid(const double *T)
{
    for (int k = 0; k < 16; k++)
        if (!isfinite(T[k])) return 0;
    if (fabs(T[12]) > BOTTOM_ROW_TOLERANCE || fabs(T[13]) > BOTTOM_ROW_TOLERANCE ||
        fabs(T[14]) > BOTTOM_ROW_TOLERANCE || fabs(T[15] - 1.0) > BOTTOM_ROW_TOLERANCE)
        return 0;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++) {
            double dot = T[a] * T[b] + T[4 + a] * T[4 + b] + T[8 + a] * T[8 + b];
            if (fabs(dot - (a == b ? 1.0 : 0.0)) > ROTATION_TOLERANCE) return 0;
        }
    /* (x cross y) . z > 0 */
    double det = (T[4] * T[9] - T[8] * T[5]) * T[2] + (T[8] * T[1] - T[0] * T[9]) * T[6] +
                 (T[0] * T[5] - T[4] * T[1]) * T[10];
    return det > 0.0;
}

static int in_reach(double r, const Params *P)
{
    return P->a2 + P->a3 + LENGTH_TOLERANCE >= r && r >= fabs(P->a2 - P->a3) - LENGTH_TOLERANCE;
}

static int within(double r, const Params *P) /* the exact reach, no tolerance; 0 for NaN */
{
    return P->a2 + P->a3 >= r && r >= fabs(P->a2 - P->a3);
}

static int reaches(double r, const Params *P) /* ik_reference._reaches: but for rounding; 0 for NaN */
{
    return P->a2 + P->a3 + REACH_ROUNDING >= r && r >= fabs(P->a2 - P->a3) - REACH_ROUNDING;
}

/* ik_reference.nearest_reachable_theta234: the theta234 nearest `theta234` that puts the
 * frame-4 origin `distance` from the shoulder (or as near as any theta234 can). R > 0. */
static double nearest_reachable_theta234(double A, double V, double theta234, double d5, double distance)
{
    const double R = hypot(A, V);
    const double u = clamp_unit((distance * distance - (R * R + d5 * d5)) / (2.0 * d5 * R));
    const double x = theta234 - atan2(V, A);
    const double first = wrap(asin(u) - x);
    const double second = wrap(PI - asin(u) - x);
    return theta234 + (fabs(first) <= fabs(second) ? first : second);
}

/* Step 1: the pose's rotation and wrist-2 point P5 = p - d6 z6 into *T; P5's distance rho from the base
 * axis, the reach A it gives and the band of A within CHOICE_TOLERANCE of rho, and theta1's band with it. */
typedef struct {
    double rho, reach, reach_low, reach_high, theta1_band;
} WristPoint;

static WristPoint wrist_point(const Params *P, const double *M, Pose *T)
{
    const double d4 = P->d4;
    WristPoint w;
    T->r11 = M[0]; T->r12 = M[1]; T->r13 = M[2];
    T->r21 = M[4]; T->r22 = M[5]; T->r23 = M[6];
    T->r31 = M[8]; T->r32 = M[9]; T->r33 = M[10];
    T->p5x = M[3] - P->d6 * M[2];
    T->p5y = M[7] - P->d6 * M[6];
    T->p5z = M[11] - P->d6 * M[10];
    const double rho2 = T->p5x * T->p5x + T->p5y * T->p5y;
    w.rho = sqrt(rho2);
    w.reach = sqrt(fmax(rho2 - d4 * d4, 0.0));
    const double low = w.rho - CHOICE_TOLERANCE, high = w.rho + CHOICE_TOLERANCE;
    w.reach_low = sqrt(fmax(low * low - d4 * d4, 0.0));
    w.reach_high = sqrt(fmax(high * high - d4 * d4, 0.0));
    w.theta1_band = (w.reach_high - w.reach_low) * d4 / (w.reach * w.reach + d4 * d4);
    return w;
}

/* |A| of both shoulder slots: the hint's where it lies in the band, else the pose's. */
static double reach_magnitude(const WristPoint *w, double reach_hint)
{
    return (w->reach_low <= fabs(reach_hint) && fabs(reach_hint) <= w->reach_high) ? fabs(reach_hint) : w->reach;
}

/* Step 2 for one theta1 (c1, s1, reach A): c5 = z4 . z6 and |s5| from the row pair of step 3 (the angles NaN). */
static Shoulder row_pair(const Pose *T, double c1, double s1, double A)
{
    Shoulder h;
    h.c1 = c1;
    h.s1 = s1;
    h.A = A;
    h.c5 = T->r13 * s1 - T->r23 * c1;
    h.c6s5 = T->r21 * c1 - T->r11 * s1;
    h.s6s5 = T->r12 * s1 - T->r22 * c1;
    h.s5_abs = sqrt(h.c6s5 * h.c6s5 + h.s6s5 * h.s6s5); /* O(1) values: no hypot needed (nor in the reference) */
    h.theta1 = h.theta5 = NAN;
    return h;
}

/* row_pair of the theta1 that puts P5 at reach A: x1 = (c1, s1) with P5 = A x1 + d4 (s1, -c1). */
static Shoulder row_pair_at_reach(const Pose *T, double rho, double d4, double A)
{
    const double scale = rho * sqrt(A * A + d4 * d4);
    return row_pair(T, (T->p5x * A - T->p5y * d4) / scale, (T->p5y * A + T->p5x * d4) / scale, A);
}

/* Where the hint's elbow angle |theta3| puts the frame-4 origin: r at that angle (NaN without a hint). */
static double hint_elbow_reach(const Params *P, double elbow_hint)
{
    return sqrt(P->a2 * P->a2 + P->a3 * P->a3 + 2.0 * P->a2 * P->a3 * cos(elbow_hint));
}

/* Steps 1 and 2 for one theta1: row_pair with theta1 and theta5 (of the wrist not flipped). */
static Shoulder with_angles(Shoulder h)
{
    h.theta1 = wrap(atan2(h.s1, h.c1));
    h.theta5 = wrap(atan2(h.s5_abs, h.c5));
    return h;
}

static Shoulder shoulder_at(const Pose *T, double c1, double s1, double A)
{
    return with_angles(row_pair(T, c1, s1, A));
}

/* Step 3's theta6 of the pose as (c6, s6), for one wrist sign; (1, 0) where s5 = 0. */
static void pose_theta6(const Shoulder *h, double sign, double *c6, double *s6)
{
    *c6 = h->s5_abs > 0.0 ? sign * h->c6s5 / h->s5_abs : 1.0;
    *s6 = h->s5_abs > 0.0 ? sign * h->s6s5 / h->s5_abs : 0.0;
}

/* Steps 4 and 5 for a wrist sign (s5 = sign |s5|) and theta6 (c6, s6): theta234 as (c234, s234), blended
 * with the third row so that it holds at every theta5, and the frame-4 origin in the arm plane (h4, v4) at r. */
static void arm_plane(const Params *P, const Pose *T, const Shoulder *h, double s5, double c6, double s6,
                      double *c234, double *s234, double *h4, double *v4, double *r)
{
    const double c1 = h->c1, s1 = h->s1, c5 = h->c5;
    const double x = s5 * (T->r13 * c1 + T->r23 * s1) + c5 * c5 * (s6 * T->r31 + c6 * T->r32);
    const double y = s5 * T->r33 + c5 * (c6 * T->r31 - s6 * T->r32);
    const double norm = sqrt(x * x + y * y);
    *c234 = x / norm;
    *s234 = y / norm;
    *h4 = h->A + P->d5 * *s234;
    *v4 = (T->p5z - P->d1) - P->d5 * *c234;
    *r = sqrt(*h4 * *h4 + *v4 * *v4);
}

/* ik_reference._wrist_and_elbow: steps 2-5 for one theta1 (its Shoulder) and one wrist sign. */
static Slot wrist_and_elbow(const Params *P, const Pose *T, const Shoulder *h, double sign, double hint)
{
    Slot o;
    const double A = h->A, c5 = h->c5;
    o.theta1 = h->theta1;
    o.s5_abs = h->s5_abs;
    const double s5 = sign * o.s5_abs;
    /* atan2(-y, x) = -atan2(y, x) exactly; wrap() sends -pi (s5 = -0, c5 < 0) to pi as it would atan2's */
    o.theta5 = sign > 0.0 ? h->theta5 : wrap(-h->theta5);
    /* Step 3: theta6 from the pose, or the hint's wherever that reproduces the pose. */
    double c6, s6;
    pose_theta6(h, sign, &c6, &s6);
    const double theta6_pose = atan2(s6, c6);
    if (o.s5_abs * fabs(wrap(hint - theta6_pose)) <= WRIST_TURN_TOLERANCE) {
        o.theta6 = hint;
        c6 = cos(hint);
        s6 = sin(hint);
    } else {
        o.theta6 = wrap(theta6_pose);
    }
    double c234, s234;
    arm_plane(P, T, h, s5, c6, s6, &c234, &s234, &o.h4, &o.v4, &o.r);
    o.theta234 = atan2(s234, c234);
    const double V = T->p5z - P->d1;
    /* a turn that could not fit the tolerance is not tried: r moves at most d5 |(A, V)| / r per radian */
    const double beyond = o.r > P->a2 + P->a3 ? o.r - (P->a2 + P->a3) : fabs(P->a2 - P->a3) - o.r;
    const double R = beyond > 0.0 ? hypot(A, V) : 0.0;
    if (beyond > 0.0 && R > 0.0 && o.s5_abs * beyond * o.r <= 2.0 * WRIST_TURN_TOLERANCE * P->d5 * R) {
        /* beyond the reach (if only just): slide along the wrist's singular direction */
        const double turn = c5 >= 0.0 ? 1.0 : -1.0;
        const double moved = nearest_reachable_theta234(A, V, o.theta234, P->d5,
                                                        o.r > P->a2 + P->a3 ? P->a2 + P->a3 : fabs(P->a2 - P->a3));
        const double theta6_moved = wrap(o.theta6 - turn * (moved - o.theta234));
        if (o.s5_abs * fabs(wrap(theta6_moved - theta6_pose)) <= WRIST_TURN_TOLERANCE) {
            o.theta234 = moved;
            o.theta6 = theta6_moved;
            o.h4 = A + P->d5 * sin(o.theta234);
            o.v4 = V - P->d5 * cos(o.theta234);
            o.r = sqrt(o.h4 * o.h4 + o.v4 * o.v4);
        }
    }
    return o;
}

/* ik_reference._reach_within_band: 1 and *slot redone with a reach A in [low, high] that puts
 * the elbow at its limit (secant steps on r(A), four evaluations at most); 0 otherwise. */
static int reach_within_band(const Params *P, const Pose *T, Slot *slot, double A, double band_a, double band_b,
                             double sign, double hint)
{
    const double outer = P->a2 + P->a3, inner = fabs(P->a2 - P->a3);
    const double low = fmin(band_a, band_b), high = fmax(band_a, band_b);
    const double rho = sqrt(T->p5x * T->p5x + T->p5y * T->p5y);
    Slot best = *slot;
    double r = slot->r;
    const double limit = r > outer ? outer : inner;
    if (!(fabs(r - limit) <= BAND_LEVERAGE * (high - low)) || fabs(slot->v4) > limit) return 0;
    double step = copysign(sqrt(limit * limit - slot->v4 * slot->v4), slot->h4) - slot->h4;
    for (int k = 0; k < 4; k++) {
        const double moved = fmin(high, fmax(low, A + step));
        if (moved == A) break;
        const double scale = rho * sqrt(moved * moved + P->d4 * P->d4);
        const double c1 = (T->p5x * moved - T->p5y * P->d4) / scale;
        const double s1 = (T->p5y * moved + T->p5x * P->d4) / scale;
        const Shoulder h = shoulder_at(T, c1, s1, moved);
        const Slot better = wrist_and_elbow(P, T, &h, sign, hint);
        if (within(better.r, P)) {
            *slot = better;
            return 1;
        }
        if (better.r != r) step = (limit - better.r) * (moved - A) / (better.r - r); /* secant on r(A) */
        if (in_reach(better.r, P) || fabs(better.r - limit) < fabs(best.r - limit)) best = better;
        A = moved;
        r = better.r;
    }
    if (!in_reach(best.r, P)) return 0;
    *slot = best;
    return 1;
}

/* ik_reference._theta1_for_reach: 1 and *better if a theta1 in its band makes the wrist reach. */
static int theta1_for_reach(const Params *P, const Pose *T, const Slot *slot, double sign, double hint, Slot *better)
{
    const double A = slot->h4 - P->d5 * sin(slot->theta234);
    const double V = T->p5z - P->d1;
    if (!isfinite(slot->r) || (A == 0.0 && V == 0.0)) return 0;
    const double moved = nearest_reachable_theta234(A, V, slot->theta234, P->d5,
                                                    slot->r > P->a2 + P->a3 ? P->a2 + P->a3 : fabs(P->a2 - P->a3));
    const double c5 = T->r13 * sin(slot->theta1) - T->r23 * cos(slot->theta1);
    const double wanted = slot->theta6 - (c5 >= 0.0 ? 1.0 : -1.0) * (moved - slot->theta234);
    const double ex = cos(wanted), ey = sin(wanted);
    double candidate = atan2(T->r21 * ey + T->r22 * ex, T->r11 * ey + T->r12 * ex);
    candidate += PI * nearbyint((slot->theta1 - candidate) / PI);
    const double c1 = cos(candidate), s1 = sin(candidate);
    if (fabs(T->p5x * s1 - T->p5y * c1 - P->d4) > CHOICE_TOLERANCE) return 0;
    const Shoulder h = shoulder_at(T, c1, s1, T->p5x * c1 + T->p5y * s1);
    *better = wrist_and_elbow(P, T, &h, sign, hint);
    return in_reach(better->r, P);
}

/* ik_reference.solve_pose for one valid pose. */
static void solve_pose(const Params *P, const double *M, double theta6_hint, double reach_hint, double theta3_hint,
                       Out o)
{
    const double d4 = P->d4, a2 = P->a2, a3 = P->a3;
    Pose T;
    const WristPoint w = wrist_point(P, M, &T);
    const double rho = w.rho;
    *o.rho = rho;
    *o.shoulder = fabs(rho - d4) <= LENGTH_TOLERANCE;
    for (int k = 0; k < 8; k++) {
        o.valid[k] = 0;
        o.wrist[k] = 0;
        o.elbow[k] = 0;
        o.failure[k] = WRIST_INSIDE_CYLINDER;
        o.elbow_distance[k] = NAN;
    }
    for (int k = 0; k < 48; k++) o.q[k] = NAN;
    if (!(rho >= d4 - LENGTH_TOLERANCE)) return;

    const double reach_low = w.reach_low, reach_high = w.reach_high;
    const double outer = a2 + a3, inner = fabs(a2 - a3);
    const double hint = wrap(theta6_hint);
    const double elbow_hint = isfinite(theta3_hint) ? fabs(wrap(theta3_hint)) : NAN;
    const double r_hint = hint_elbow_reach(P, elbow_hint);
    for (int i = 0; i < 2; i++) {
        const double side = i == 0 ? -1.0 : 1.0;
        const double A = side * reach_magnitude(&w, reach_hint);
        const Shoulder h = with_angles(row_pair_at_reach(&T, rho, d4, A));
        for (int j = 0; j < 2; j++) {
            const double sign = j == 0 ? 1.0 : -1.0;
            Slot s = wrist_and_elbow(P, &T, &h, sign, hint);
            if (!reaches(s.r, P)) {
                /* where the band holds A = 0 the two shoulder slots are one branch: either may cross */
                const double band_a = reach_low > 0.0 ? side * reach_low : -side * reach_high;
                reach_within_band(P, &T, &s, A, band_a, side * reach_high, sign, hint);
            }
            if (!reaches(s.r, P)) { /* the hint's theta6 kept at a tiny |s5|: the pose's own may reach */
                const Slot own = wrist_and_elbow(P, &T, &h, sign, NAN);
                if (reaches(own.r, P)) s = own;
            }
            if (!reaches(s.r, P) && s.s5_abs <= w.theta1_band) {
                Slot better;
                if (theta1_for_reach(P, &T, &s, sign, hint, &better)) s = better;
            }
            const int base = 4 * i + 2 * j;
            o.elbow_distance[base] = o.elbow_distance[base + 1] = s.r;
            o.wrist[base] = o.wrist[base + 1] = (npy_bool)(s.s5_abs <= WRIST_TOLERANCE);
            if (!(s.r <= outer + LENGTH_TOLERANCE)) { /* NaN too: a target so far that r overflowed */
                o.failure[base] = o.failure[base + 1] = ELBOW_TOO_FAR;
                continue;
            }
            if (s.r < inner - LENGTH_TOLERANCE) {
                o.failure[base] = o.failure[base + 1] = ELBOW_TOO_CLOSE;
                continue;
            }
            const int at_limit = s.r >= outer - LENGTH_TOLERANCE || s.r <= inner + LENGTH_TOLERANCE;
            double c3 = clamp_unit((s.r * s.r - a2 * a2 - a3 * a3) / (2.0 * a2 * a3));
            double s3 = sqrt(1.0 - c3 * c3);
            double theta3 = atan2(s3, c3);
            if (fabs(s.r - r_hint) <= CHOICE_TOLERANCE) { /* theta3 is fixed only to sqrt(rounding) at the limits */
                theta3 = elbow_hint;
                c3 = cos(elbow_hint);
                s3 = sin(elbow_hint);
            }
            const double beta = atan2(s.v4, s.h4);
            const double gamma = atan2(a3 * s3, a2 + a3 * c3);
            for (int l = 0; l < 2; l++) {
                const int k = base + l;
                const double t3 = wrap(l == 0 ? theta3 : -theta3);
                const double t2 = wrap(l == 0 ? beta - gamma : beta + gamma);
                double *qk = o.q + 6 * k;
                qk[0] = s.theta1;
                qk[1] = t2;
                qk[2] = t3;
                qk[3] = wrap(s.theta234 - t2 - t3);
                qk[4] = s.theta5;
                qk[5] = s.theta6;
                o.valid[k] = 1;
                o.elbow[k] = (npy_bool)at_limit;
                o.failure[k] = REACHABLE;
            }
        }
    }
}

/* ---------------------------------------------------------------- many poses side by side
 * solve_pose is one long chain of dependent steps, about half its time the C library's atan2: one
 * pose at a time, the processor waits on each. ik_batch hands solve_lanes LANES poses at once: each step
 * of the regular case (no slot near a singularity, a hint or a tolerance's edge) runs over all of
 * them before the next, so their chains overlap, with lane_atan2 (below) for the angles. A pose
 * with any slot that is not regular is solved again by solve_pose: every decision is then
 * solve_pose's own, and the angles differ from its by an ulp or so. */
#define LANES 8

/* atan2 for the lanes: Cephes' rational approximation of atan on [0, 0.66] after two reductions
 * (min/max, and (t - 1)/(t + 1) above 0.66), within 2 ulp of the C library's; no branch a pose's
 * numbers could make slow. NaN where both are zero (such a slot is left to solve_pose). pi_low is
 * pi - PI, what the double PI leaves out, added back where a multiple of pi/4 is. */
static inline double lane_atan2(double y, double x, double pi_low)
{
    const double ax = fabs(x), ay = fabs(y);
    const int swap = ay > ax;
    const double t = (swap ? ax : ay) / (swap ? ay : ax);
    const int upper = t > 0.66;
    const double u = (upper ? t - 1.0 : t) / (upper ? t + 1.0 : 1.0);
    const double z = u * u;
    const double p = (((-0.8750608600031904122785 * z - 16.15753718733365076637) * z - 75.00855792314704667340) * z
                      - 122.8866684490136173410) * z - 64.85021904942025371773;
    const double q = ((((z + 24.85846490142306297962) * z + 165.0270098316988542046) * z + 432.8810604912902668951) * z
                      + 485.3903996359136964868) * z + 194.5506571482613964425;
    double angle = (upper ? PI / 4 : 0.0) + (u * (z * p / q) + u + (upper ? 0.25 * pi_low : 0.0));
    angle = swap ? (PI / 2 - angle) + 0.5 * pi_low : angle;
    angle = x < 0.0 ? (PI - angle) + pi_low : angle;
    return copysign(angle, y);
}

static void solve_lanes(const Params *P, const double *const *M, const double *theta6_hint, const double *reach_hint,
                        const double *theta3_hint, const Out *o, int lanes)
{
    const double a2 = P->a2, a3 = P->a3, d4 = P->d4, d5 = P->d5;
    const double outer = a2 + a3, inner = fabs(a2 - a3);
    int regular[LANES];
    Pose T[LANES];
    WristPoint w[LANES];
    Shoulder h[LANES][2]; /* per lane and side i */
    double hint[LANES], r_hint[LANES];
    /* per lane and slot pair k = 2 i + j (side i, wrist sign j) */
    double c6[LANES][4], s6[LANES][4], c234[LANES][4], s234[LANES][4], h4[LANES][4], v4[LANES][4], r[LANES][4];
    double c3[LANES][4], s3[LANES][4];
    double theta1[LANES][2], theta5[LANES][2]; /* per side */
    double theta6[LANES][4], theta234[LANES][4], theta3[LANES][4], beta[LANES][4], gamma[LANES][4];
    /* an angle this near +-pi may come out as the other one (2 pi away) where the library's atan2 and
     * lane_atan2 differ by an ulp: such a pose is left to solve_pose. 2^-46 is 32 ulp of pi. */
    const double edge = PI - ldexp(1.0, -46);
    const double pi_low = sin(PI); /* pi - PI, exactly as a double: sin(pi - x) = x to x^3 / 6 */

    for (int l = 0; l < lanes; l++) { /* steps 1 and 2 */
        w[l] = wrist_point(P, M[l], &T[l]);
        *o[l].rho = w[l].rho;
        *o[l].shoulder = fabs(w[l].rho - d4) <= LENGTH_TOLERANCE;
        regular[l] = w[l].rho >= d4 - LENGTH_TOLERANCE;
        hint[l] = wrap(theta6_hint[l]);
        r_hint[l] = hint_elbow_reach(P, isfinite(theta3_hint[l]) ? fabs(wrap(theta3_hint[l])) : NAN);
        const double magnitude = reach_magnitude(&w[l], reach_hint[l]);
        for (int i = 0; i < 2; i++) h[l][i] = row_pair_at_reach(&T[l], w[l].rho, d4, (i == 0 ? -1.0 : 1.0) * magnitude);
    }
    for (int l = 0; l < lanes; l++) /* steps 3-5 of each slot pair, the pose's own theta6 */
        for (int k = 0; k < 4; k++) {
            const Shoulder *hk = &h[l][k >> 1];
            const double sign = (k & 1) ? -1.0 : 1.0;
            pose_theta6(hk, sign, &c6[l][k], &s6[l][k]);
            arm_plane(P, &T[l], hk, sign * hk->s5_abs, c6[l][k], s6[l][k], &c234[l][k], &s234[l][k], &h4[l][k], &v4[l][k],
                      &r[l][k]);
            const double cc = clamp_unit((r[l][k] * r[l][k] - a2 * a2 - a3 * a3) / (2.0 * a2 * a3));
            c3[l][k] = cc;
            s3[l][k] = sqrt(1.0 - cc * cc);
        }
    for (int l = 0; l < lanes; l++) /* every angle, side by side */
        for (int k = 0; k < 4; k++) {
            if (!(k & 1)) {
                theta1[l][k >> 1] = lane_atan2(h[l][k >> 1].s1, h[l][k >> 1].c1, pi_low);
                theta5[l][k >> 1] = lane_atan2(h[l][k >> 1].s5_abs, h[l][k >> 1].c5, pi_low);
            }
            theta6[l][k] = lane_atan2(s6[l][k], c6[l][k], pi_low);
            theta234[l][k] = lane_atan2(s234[l][k], c234[l][k], pi_low);
            theta3[l][k] = lane_atan2(s3[l][k], c3[l][k], pi_low);
            beta[l][k] = lane_atan2(v4[l][k], h4[l][k], pi_low);
            gamma[l][k] = lane_atan2(a3 * s3[l][k], a2 + a3 * c3[l][k], pi_low);
        }
    for (int l = 0; l < lanes; l++) { /* where solve_pose would decide otherwise, or the angles may differ */
        for (int k = 0; k < 4 && regular[l]; k++) {
            const double side = k < 2 ? -1.0 : 1.0, rk = r[l][k], s5 = h[l][k >> 1].s5_abs, A = h[l][k >> 1].A;
            const double V = T[l].p5z - P->d1;
            /* the hint's theta6 kept (with a margin for the ulp lane_atan2 may differ by) */
            int ok = s5 * fabs(wrap(hint[l] - theta6[l][k])) > 2.0 * WRIST_TURN_TOLERANCE;
            ok = ok && !(fabs(rk - r_hint[l]) <= CHOICE_TOLERANCE); /* the hint's theta3 kept */
            /* wrist_and_elbow's slide along the singular direction (sqrt for hypot: a margin of 2) */
            const double beyond = rk > outer ? rk - outer : inner - rk;
            ok = ok && isfinite(rk) && !(beyond > 0.0 && s5 * beyond * rk <= 4.0 * WRIST_TURN_TOLERANCE * d5 *
                                                                           sqrt(A * A + V * V));
            if (ok && !reaches(rk, P)) { /* reach_within_band would start; theta1_for_reach would be tried */
                const double band_a = w[l].reach_low > 0.0 ? side * w[l].reach_low : -side * w[l].reach_high;
                const double band_b = side * w[l].reach_high;
                const double limit = rk > outer ? outer : inner;
                ok = (!(fabs(rk - limit) <= BAND_LEVERAGE * (fmax(band_a, band_b) - fmin(band_a, band_b))) ||
                      fabs(v4[l][k]) > limit) && !(s5 <= w[l].theta1_band);
            }
            regular[l] = ok;
        }
        const Out out = o[l];
        for (int k = 0; k < 48; k++) out.q[k] = NAN;
        for (int k = 0; k < 4; k++) {
            const int base = 2 * k;
            const double rk = r[l][k];
            out.elbow_distance[base] = out.elbow_distance[base + 1] = rk;
            out.wrist[base] = out.wrist[base + 1] = (npy_bool)(h[l][k >> 1].s5_abs <= WRIST_TOLERANCE);
            out.valid[base] = out.valid[base + 1] = 0;
            out.elbow[base] = out.elbow[base + 1] = 0;
            if (!(rk <= outer + LENGTH_TOLERANCE) || rk < inner - LENGTH_TOLERANCE) {
                out.failure[base] = out.failure[base + 1] = rk < inner - LENGTH_TOLERANCE ? ELBOW_TOO_CLOSE : ELBOW_TOO_FAR;
                continue;
            }
            const int at_limit = rk >= outer - LENGTH_TOLERANCE || rk <= inner + LENGTH_TOLERANCE;
            const double t1 = wrap(theta1[l][k >> 1]);
            const double t5 = (k & 1) ? wrap(-wrap(theta5[l][k >> 1])) : wrap(theta5[l][k >> 1]);
            const double t6 = wrap(theta6[l][k]);
            for (int e = 0; e < 2; e++) {
                double *qk = out.q + 6 * (base + e);
                const double t3 = wrap(e == 0 ? theta3[l][k] : -theta3[l][k]);
                const double t2 = wrap(e == 0 ? beta[l][k] - gamma[l][k] : beta[l][k] + gamma[l][k]);
                qk[0] = t1;
                qk[1] = t2;
                qk[2] = t3;
                qk[3] = wrap(theta234[l][k] - t2 - t3);
                qk[4] = t5;
                qk[5] = t6;
                out.valid[base + e] = 1;
                out.elbow[base + e] = (npy_bool)at_limit;
                out.failure[base + e] = REACHABLE;
                for (int joint = 0; joint < 6; joint++) regular[l] = regular[l] && fabs(qk[joint]) <= edge;
            }
        }
        if (!regular[l]) solve_pose(P, M[l], theta6_hint[l], reach_hint[l], theta3_hint[l], out);
    }
}

static int check_configured(void)
{
    if (!configured) PyErr_SetString(PyExc_RuntimeError, "_kernels.set_tolerances() was not called");
    return configured;
}

/* set_tolerances(length, choice, wrist_turn, wrist, rotation, bottom_row, band_leverage, reach_rounding, side,
 * stretched, limit, square_rounding): ur10core/tolerances.py. */
static PyObject *set_tolerances(PyObject *self, PyObject *args)
{
    if (!PyArg_ParseTuple(args, "dddddddddddd", &LENGTH_TOLERANCE, &CHOICE_TOLERANCE, &WRIST_TURN_TOLERANCE,
                          &WRIST_TOLERANCE, &ROTATION_TOLERANCE, &BOTTOM_ROW_TOLERANCE, &BAND_LEVERAGE,
                          &REACH_ROUNDING, &SIDE_TOLERANCE, &STRETCHED_TOLERANCE, &LIMIT_TOLERANCE,
                          &SQUARE_ROUNDING))
        return NULL;
    configured = 1;
    Py_RETURN_NONE;
}

static int parse_params(PyObject *tuple, Params *P)
{
    return PyArg_ParseTuple(tuple, "dddddd", &P->d1, &P->a2, &P->a3, &P->d4, &P->d5, &P->d6);
}

static int is_c_array(PyObject *obj, int typenum)
{
    return PyArray_Check(obj) && PyArray_TYPE((PyArrayObject *)obj) == typenum &&
           PyArray_IS_C_CONTIGUOUS((PyArrayObject *)obj);
}

/* ik_one(T, theta6_hint, reach_hint, theta3_hint, params) -> tuple of arrays, or None when T is not
 * a valid pose. T must be a C-contiguous float64 (4, 4) array (the caller guarantees it). */
static PyObject *ik_one(PyObject *self, PyObject *args)
{
    PyObject *T_obj, *params;
    double hint, reach_hint, theta3_hint;
    Params P;
    if (!check_configured()) return NULL;
    if (!PyArg_ParseTuple(args, "OdddO", &T_obj, &hint, &reach_hint, &theta3_hint, &params)) return NULL;
    if (!parse_params(params, &P)) return NULL;
    if (!is_c_array(T_obj, NPY_DOUBLE) || PyArray_SIZE((PyArrayObject *)T_obj) != 16) {
        PyErr_SetString(PyExc_TypeError, "ik_one needs a C-contiguous float64 (4, 4) array");
        return NULL;
    }
    const double *T = (const double *)PyArray_DATA((PyArrayObject *)T_obj);
    if (!pose_is_valid(T)) Py_RETURN_NONE;

    npy_intp dims_q[2] = {8, 6}, dims8[1] = {8};
    PyObject *q = PyArray_SimpleNew(2, dims_q, NPY_DOUBLE);
    PyObject *valid = PyArray_SimpleNew(1, dims8, NPY_BOOL);
    PyObject *wrist = PyArray_SimpleNew(1, dims8, NPY_BOOL);
    PyObject *elbow = PyArray_SimpleNew(1, dims8, NPY_BOOL);
    PyObject *shoulder = PyArray_SimpleNew(0, NULL, NPY_BOOL);
    PyObject *failure = PyArray_SimpleNew(1, dims8, NPY_INT8);
    PyObject *rho = PyArray_SimpleNew(0, NULL, NPY_DOUBLE);
    PyObject *distance = PyArray_SimpleNew(1, dims8, NPY_DOUBLE);
    if (!q || !valid || !wrist || !elbow || !shoulder || !failure || !rho || !distance) {
        Py_XDECREF(q); Py_XDECREF(valid); Py_XDECREF(wrist); Py_XDECREF(elbow);
        Py_XDECREF(shoulder); Py_XDECREF(failure); Py_XDECREF(rho); Py_XDECREF(distance);
        return NULL;
    }
    Out o = {
        (double *)PyArray_DATA((PyArrayObject *)q),
        (npy_bool *)PyArray_DATA((PyArrayObject *)valid),
        (npy_bool *)PyArray_DATA((PyArrayObject *)wrist),
        (npy_bool *)PyArray_DATA((PyArrayObject *)elbow),
        (npy_int8 *)PyArray_DATA((PyArrayObject *)failure),
        (double *)PyArray_DATA((PyArrayObject *)distance),
        (double *)PyArray_DATA((PyArrayObject *)rho),
        (npy_bool *)PyArray_DATA((PyArrayObject *)shoulder),
    };
    solve_pose(&P, T, hint, reach_hint, theta3_hint, o);
    return Py_BuildValue("(NNNNNNNN)", q, valid, wrist, elbow, shoulder, failure, rho, distance);
}

/* ik_batch(T (n,4,4), theta6_hint (n,), reach_hint (n,), theta3_hint (n,), params, q (n,8,6), valid, wrist, elbow (n,8) bool,
 *          shoulder (n,) bool, failure (n,8) int8, rho (n,), distance (n,8)) -> int
 * Solves every pose without the GIL; returns the index of the first pose that is not
 * a valid transform (the caller raises; such a pose's outputs are not written), or -1. */
static PyObject *ik_batch(PyObject *self, PyObject *args)
{
    PyObject *T_obj, *hint_obj, *reach_obj, *elbow_obj, *params, *q, *valid, *wrist, *elbow, *shoulder, *failure,
        *rho, *distance;
    Params P;
    if (!check_configured()) return NULL;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOOOO", &T_obj, &hint_obj, &reach_obj, &elbow_obj, &params, &q, &valid,
                          &wrist, &elbow, &shoulder, &failure, &rho, &distance))
        return NULL;
    if (!parse_params(params, &P)) return NULL;
    if (!is_c_array(T_obj, NPY_DOUBLE) || !is_c_array(hint_obj, NPY_DOUBLE) || !is_c_array(reach_obj, NPY_DOUBLE) ||
        !is_c_array(elbow_obj, NPY_DOUBLE) ||
        !is_c_array(q, NPY_DOUBLE) || !is_c_array(valid, NPY_BOOL) ||
        !is_c_array(wrist, NPY_BOOL) || !is_c_array(elbow, NPY_BOOL) ||
        !is_c_array(shoulder, NPY_BOOL) || !is_c_array(failure, NPY_INT8) ||
        !is_c_array(rho, NPY_DOUBLE) || !is_c_array(distance, NPY_DOUBLE)) {
        PyErr_SetString(PyExc_TypeError, "ik_batch needs C-contiguous arrays of the documented dtypes");
        return NULL;
    }
    npy_intp n = PyArray_SIZE((PyArrayObject *)T_obj) / 16;
    if (PyArray_SIZE((PyArrayObject *)T_obj) != 16 * n || PyArray_SIZE((PyArrayObject *)hint_obj) != n ||
        PyArray_SIZE((PyArrayObject *)reach_obj) != n || PyArray_SIZE((PyArrayObject *)elbow_obj) != n ||
        PyArray_SIZE((PyArrayObject *)q) != 48 * n || PyArray_SIZE((PyArrayObject *)valid) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)wrist) != 8 * n || PyArray_SIZE((PyArrayObject *)elbow) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)shoulder) != n || PyArray_SIZE((PyArrayObject *)failure) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)rho) != n || PyArray_SIZE((PyArrayObject *)distance) != 8 * n) {
        PyErr_SetString(PyExc_ValueError, "ik_batch: output sizes do not match the number of poses");
        return NULL;
    }
    const double *T = (const double *)PyArray_DATA((PyArrayObject *)T_obj);
    const double *hint = (const double *)PyArray_DATA((PyArrayObject *)hint_obj);
    const double *reach_hint = (const double *)PyArray_DATA((PyArrayObject *)reach_obj);
    const double *theta3_hint = (const double *)PyArray_DATA((PyArrayObject *)elbow_obj);
    double *q_data = (double *)PyArray_DATA((PyArrayObject *)q);
    npy_bool *valid_data = (npy_bool *)PyArray_DATA((PyArrayObject *)valid);
    npy_bool *wrist_data = (npy_bool *)PyArray_DATA((PyArrayObject *)wrist);
    npy_bool *elbow_data = (npy_bool *)PyArray_DATA((PyArrayObject *)elbow);
    npy_bool *shoulder_data = (npy_bool *)PyArray_DATA((PyArrayObject *)shoulder);
    npy_int8 *failure_data = (npy_int8 *)PyArray_DATA((PyArrayObject *)failure);
    double *rho_data = (double *)PyArray_DATA((PyArrayObject *)rho);
    double *distance_data = (double *)PyArray_DATA((PyArrayObject *)distance);
    npy_intp first_bad = -1;

    Py_BEGIN_ALLOW_THREADS
    const double *lane_pose[LANES];
    double lane_hint[LANES], lane_reach[LANES], lane_theta3[LANES];
    Out lane_out[LANES];
    int lanes = 0;
    for (npy_intp m = 0; m < n; m++) {
        const double *Tm = T + 16 * m;
        if (!pose_is_valid(Tm)) {
            if (first_bad < 0) first_bad = m;
        } else {
            const Out o = {q_data + 48 * m, valid_data + 8 * m, wrist_data + 8 * m, elbow_data + 8 * m,
                           failure_data + 8 * m, distance_data + 8 * m, rho_data + m, shoulder_data + m};
            lane_pose[lanes] = Tm;
            lane_hint[lanes] = hint[m];
            lane_reach[lanes] = reach_hint[m];
            lane_theta3[lanes] = theta3_hint[m];
            lane_out[lanes++] = o;
        }
        if (lanes == LANES || (m == n - 1 && lanes > 0)) {
            solve_lanes(&P, lane_pose, lane_hint, lane_reach, lane_theta3, lane_out, lanes);
            lanes = 0;
        }
    }
    Py_END_ALLOW_THREADS

    return PyLong_FromSsize_t(first_bad);
}

/* The arguments (q, params) of a one-pose call `name`: 1 with *P and *q set, 0 if q is not finite,
 * -1 with an exception set. q must be a C-contiguous float64 array of 6 angles. */
static int one_joint_vector(PyObject *args, const char *name, Params *P, const double **q)
{
    PyObject *q_obj, *params;
    if (!PyArg_ParseTuple(args, "OO", &q_obj, &params)) return -1;
    if (!parse_params(params, P)) return -1;
    if (!is_c_array(q_obj, NPY_DOUBLE) || PyArray_SIZE((PyArrayObject *)q_obj) != 6) {
        PyErr_Format(PyExc_TypeError, "%s needs a C-contiguous float64 array of 6 angles", name);
        return -1;
    }
    *q = (const double *)PyArray_DATA((PyArrayObject *)q_obj);
    for (int k = 0; k < 6; k++)
        if (!isfinite((*q)[k])) return 0;
    return 1;
}

/* The arguments (q (n, 6), params, out (n, ...)) of a batch call `name` writing `per_pose` values a
 * joint vector (`shape` names them in the message): 1 with everything set, 0 with an exception. */
static int joint_batch(PyObject *args, const char *name, npy_intp per_pose, const char *shape, Params *P,
                       const double **q, double **out, npy_intp *n)
{
    PyObject *q_obj, *params, *out_obj;
    if (!PyArg_ParseTuple(args, "OOO", &q_obj, &params, &out_obj)) return 0;
    if (!parse_params(params, P)) return 0;
    if (!is_c_array(q_obj, NPY_DOUBLE) || !is_c_array(out_obj, NPY_DOUBLE)) {
        PyErr_Format(PyExc_TypeError, "%s needs C-contiguous float64 arrays", name);
        return 0;
    }
    *n = PyArray_SIZE((PyArrayObject *)q_obj) / 6;
    if (PyArray_SIZE((PyArrayObject *)q_obj) != 6 * *n || PyArray_SIZE((PyArrayObject *)out_obj) != per_pose * *n) {
        PyErr_Format(PyExc_ValueError, "%s: q must hold n x 6 angles and out n x %s", name, shape);
        return 0;
    }
    *q = (const double *)PyArray_DATA((PyArrayObject *)q_obj);
    *out = (double *)PyArray_DATA((PyArrayObject *)out_obj);
    return 1;
}

/* fk_one(q, params) -> (4, 4) array T06 in closed form (docs/kinematics.md §3), or None if q is
 * not finite. q must be a C-contiguous float64 array of 6 joint angles. */
static PyObject *fk_one(PyObject *self, PyObject *args)
{
    Params P;
    const double *q;
    const int read = one_joint_vector(args, "fk_one", &P, &q);
    if (read < 0) return NULL;
    if (read == 0) Py_RETURN_NONE;
    const double c1 = cos(q[0]), s1 = sin(q[0]), c2 = cos(q[1]), s2 = sin(q[1]);
    const double c5 = cos(q[4]), s5 = sin(q[4]), c6 = cos(q[5]), s6 = sin(q[5]);
    const double c23 = cos(q[1] + q[2]), s23 = sin(q[1] + q[2]);
    const double c234 = cos(q[1] + q[2] + q[3]), s234 = sin(q[1] + q[2] + q[3]);
    const double u = -s1 * s5 + c1 * c5 * c234, w = s5 * c1 + s1 * c5 * c234;
    const double r13 = s1 * c5 + s5 * c1 * c234, r23 = -c1 * c5 + s5 * s1 * c234, r33 = s5 * s234;
    const double reach = P.a2 * c2 + P.a3 * c23 - P.d5 * s234;
    npy_intp dims[2] = {4, 4};
    PyObject *T_obj = PyArray_SimpleNew(2, dims, NPY_DOUBLE);
    if (!T_obj) return NULL;
    double *T = (double *)PyArray_DATA((PyArrayObject *)T_obj);
    T[0] = c6 * u - s6 * s234 * c1;
    T[1] = -s6 * u - s234 * c1 * c6;
    T[2] = r13;
    T[3] = c1 * reach + P.d4 * s1 + P.d6 * r13;
    T[4] = c6 * w - s6 * s234 * s1;
    T[5] = -s6 * w - s234 * s1 * c6;
    T[6] = r23;
    T[7] = s1 * reach - P.d4 * c1 + P.d6 * r23;
    T[8] = s6 * c234 + s234 * c5 * c6;
    T[9] = c6 * c234 - s234 * c5 * s6;
    T[10] = r33;
    T[11] = P.a2 * s2 + P.a3 * s23 + P.d1 + P.d5 * c234 + P.d6 * r33;
    T[12] = T[13] = T[14] = 0.0;
    T[15] = 1.0;
    return T_obj;
}

/* Frames {0}..{6} of one joint vector into F (7 x 16, row-major 4 x 4): T0i = T01 T12 ... T(i-1,i)
 * of the course's modified DH table (docs/kinematics.md §2). */
static void chain_frames(const double *q, const Params *P, double *F)
{
    /* alpha_{i-1}: 0, +pi/2, 0, 0, -pi/2, +pi/2 as (cos, sin); a_{i-1}; d_i */
    static const double ca[6] = {1.0, 0.0, 1.0, 1.0, 0.0, 0.0}, sa[6] = {0.0, 1.0, 0.0, 0.0, -1.0, 1.0};
    const double a[6] = {0.0, 0.0, P->a2, P->a3, 0.0, 0.0}, d[6] = {P->d1, 0.0, 0.0, P->d4, P->d5, P->d6};
    for (int k = 0; k < 16; k++) F[k] = (k % 5 == 0) ? 1.0 : 0.0; /* frame {0} = I */
    for (int i = 0; i < 6; i++) {
        const double ct = cos(q[i]), st = sin(q[i]);
        /* T(i-1,i) = RotX(alpha) TransX(a) RotZ(theta) TransZ(d) */
        const double L[12] = {ct, -st, 0.0, a[i],
                              st * ca[i], ct * ca[i], -sa[i], -sa[i] * d[i],
                              st * sa[i], ct * sa[i], ca[i], ca[i] * d[i]};
        const double *A = F + 16 * i;
        double *B = F + 16 * (i + 1);
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 4; c++) {
                double v = A[4 * r + 0] * L[c] + A[4 * r + 1] * L[4 + c] + A[4 * r + 2] * L[8 + c];
                B[4 * r + c] = c == 3 ? v + A[4 * r + 3] : v;
            }
        }
        B[12] = B[13] = B[14] = 0.0;
        B[15] = 1.0;
    }
}

/* The geometric Jacobian (6 x 6, row-major, rows [v; w]) at the flange origin from the frames F:
 * column i is [z_i x (o_6 - o_i); z_i] (docs/kinematics.md §5). */
static void jacobian_from_frames(const double *F, double *J)
{
    const double *o6 = F + 16 * 6;
    for (int i = 0; i < 6; i++) {
        const double *Fi = F + 16 * (i + 1);
        const double zx = Fi[2], zy = Fi[6], zz = Fi[10];
        const double dx = o6[3] - Fi[3], dy = o6[7] - Fi[7], dz = o6[11] - Fi[11];
        J[i] = zy * dz - zz * dy;
        J[6 + i] = zz * dx - zx * dz;
        J[12 + i] = zx * dy - zy * dx;
        J[18 + i] = zx;
        J[24 + i] = zy;
        J[30 + i] = zz;
    }
}

/* frames(q (n, 6), params, out (n, 7, 4, 4)): chain_frames of every joint vector; ur10core.arm.Arm.frames. */
static PyObject *frames(PyObject *self, PyObject *args)
{
    Params P;
    const double *q;
    double *out;
    npy_intp n;
    if (!joint_batch(args, "frames", 112, "7 x 4 x 4", &P, &q, &out, &n)) return NULL;
    Py_BEGIN_ALLOW_THREADS
    for (npy_intp m = 0; m < n; m++) chain_frames(q + 6 * m, &P, out + 112 * m);
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

/* jacobians(q (n, 6), params, out (n, 6, 6)): the flange Jacobian of every joint vector; Arm.jacobian. */
static PyObject *jacobians(PyObject *self, PyObject *args)
{
    Params P;
    const double *q;
    double *out;
    npy_intp n;
    double F[112];
    if (!joint_batch(args, "jacobians", 36, "6 x 6", &P, &q, &out, &n)) return NULL;
    Py_BEGIN_ALLOW_THREADS
    for (npy_intp m = 0; m < n; m++) {
        chain_frames(q + 6 * m, &P, F);
        jacobian_from_frames(F, out + 36 * m);
    }
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

/* jacobian_one(q, params) -> (6, 6) array, or None if q is not finite. q must be a C-contiguous
 * float64 array of 6 angles (the caller's fast path checks it). */
static PyObject *jacobian_one(PyObject *self, PyObject *args)
{
    Params P;
    const double *q;
    const int read = one_joint_vector(args, "jacobian_one", &P, &q);
    if (read < 0) return NULL;
    if (read == 0) Py_RETURN_NONE;
    npy_intp dims[2] = {6, 6};
    PyObject *J_obj = PyArray_SimpleNew(2, dims, NPY_DOUBLE);
    if (!J_obj) return NULL;
    double F[112];
    chain_frames(q, &P, F);
    jacobian_from_frames(F, (double *)PyArray_DATA((PyArrayObject *)J_obj));
    return J_obj;
}

/* quaternions(R (n, 3, 3), out (n, 4)): unit (w, x, y, z), w >= 0, by Shepperd's method;
 * ur10core.orientation.quaternion. */
static PyObject *quaternions(PyObject *self, PyObject *args)
{
    PyObject *R_obj, *out_obj;
    if (!PyArg_ParseTuple(args, "OO", &R_obj, &out_obj)) return NULL;
    if (!is_c_array(R_obj, NPY_DOUBLE) || !is_c_array(out_obj, NPY_DOUBLE)) {
        PyErr_SetString(PyExc_TypeError, "quaternions needs C-contiguous float64 arrays");
        return NULL;
    }
    const npy_intp n = PyArray_SIZE((PyArrayObject *)R_obj) / 9;
    if (PyArray_SIZE((PyArrayObject *)R_obj) != 9 * n || PyArray_SIZE((PyArrayObject *)out_obj) != 4 * n) {
        PyErr_SetString(PyExc_ValueError, "quaternions: R must hold n x 3 x 3 and out n x 4");
        return NULL;
    }
    const double *R = (const double *)PyArray_DATA((PyArrayObject *)R_obj);
    double *out = (double *)PyArray_DATA((PyArrayObject *)out_obj);
    for (npy_intp m = 0; m < n; m++) {
        const double *r = R + 9 * m;
        double *q = out + 4 * m;
        const double trace = r[0] + r[4] + r[8];
        /* row k is 4 q_k q; divide by the largest q_k */
        const double diag[4] = {1.0 + trace, 1.0 + r[0] - r[4] - r[8], 1.0 - r[0] + r[4] - r[8], 1.0 - r[0] - r[4] + r[8]};
        int k = 0;
        for (int i = 1; i < 4; i++)
            if (diag[i] > diag[k]) k = i;
        double v[4];
        switch (k) {
        case 0: v[0] = diag[0]; v[1] = r[7] - r[5]; v[2] = r[2] - r[6]; v[3] = r[3] - r[1]; break;
        case 1: v[0] = r[7] - r[5]; v[1] = diag[1]; v[2] = r[1] + r[3]; v[3] = r[2] + r[6]; break;
        case 2: v[0] = r[2] - r[6]; v[1] = r[1] + r[3]; v[2] = diag[2]; v[3] = r[5] + r[7]; break;
        default: v[0] = r[3] - r[1]; v[1] = r[2] + r[6]; v[2] = r[5] + r[7]; v[3] = diag[3]; break;
        }
        double norm = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        if (v[0] < 0.0) norm = -norm;
        for (int i = 0; i < 4; i++) q[i] = v[i] / norm;
    }
    Py_RETURN_NONE;
}

/* nearest_one(q (8, 6), valid (8,) bool, current (6,), joint_limit, prefer, tie) -> (slot, shifted (6,))
 * ur10core.ik.nearest_branch for one pose: every angle of every valid slot moved to its
 * 2pi-equivalent nearest the current one, moved by whole turns into +-joint_limit (>= pi),
 * the slot with the smallest squared joint distance (first on ties, as numpy's argmin),
 * kept as `prefer` when that is within `tie` of it. slot -1 (and NaN angles) when no slot
 * is valid. prefer < 0 means no preference. */
static PyObject *nearest_one(PyObject *self, PyObject *args)
{
    PyObject *q_obj, *valid_obj, *current_obj;
    double limit, tie;
    int prefer;
    if (!PyArg_ParseTuple(args, "OOOdid", &q_obj, &valid_obj, &current_obj, &limit, &prefer, &tie)) return NULL;
    if (!is_c_array(q_obj, NPY_DOUBLE) || PyArray_SIZE((PyArrayObject *)q_obj) != 48 ||
        !is_c_array(valid_obj, NPY_BOOL) || PyArray_SIZE((PyArrayObject *)valid_obj) != 8 ||
        !is_c_array(current_obj, NPY_DOUBLE) || PyArray_SIZE((PyArrayObject *)current_obj) != 6) {
        PyErr_SetString(PyExc_TypeError, "nearest_one needs C-contiguous q (8, 6) float64, valid (8,) bool, current (6,) float64");
        return NULL;
    }
    const double *q = (const double *)PyArray_DATA((PyArrayObject *)q_obj);
    const npy_bool *valid = (const npy_bool *)PyArray_DATA((PyArrayObject *)valid_obj);
    const double *current = (const double *)PyArray_DATA((PyArrayObject *)current_obj);
    double shifted[48], distance[8];
    int best = -1;
    for (int k = 0; k < 8; k++) {
        distance[k] = INFINITY;
        if (!valid[k]) continue;
        double sum = 0.0;
        for (int j = 0; j < 6; j++) {
            const double angle = q[6 * k + j];
            double v = angle + TAU * nearbyint((current[j] - angle) / TAU); /* half to even, as np.round */
            if (v > limit)
                v -= TAU * ceil((v - limit) / TAU);
            else if (v < -limit)
                v += TAU * ceil((-limit - v) / TAU);
            shifted[6 * k + j] = v;
            sum += (v - current[j]) * (v - current[j]);
        }
        if (!isfinite(sum)) continue; /* never chosen, as an invalid slot */
        distance[k] = sum;
        if (best < 0 || sum < distance[best]) best = k;
    }
    npy_intp dims[1] = {6};
    PyObject *out = PyArray_SimpleNew(1, dims, NPY_DOUBLE);
    if (!out) return NULL;
    double *o = (double *)PyArray_DATA((PyArrayObject *)out);
    if (best < 0) {
        for (int j = 0; j < 6; j++) o[j] = NAN;
        return Py_BuildValue("(iN)", -1, out);
    }
    if (prefer >= 0 && prefer < 8 && distance[prefer] <= distance[best] + tie) best = prefer;
    for (int j = 0; j < 6; j++) o[j] = shifted[6 * best + j];
    return Py_BuildValue("(iN)", best, out);
}

/* ------------------------------------------------------------------------------------------------
 * The spherical-wrist arms (KR210, the elbow arm, the Stanford arm and any table of their shape):
 * ur10core/solvers/spherical_wrist.py's _solve_one, step for step, for one pose or a batch.
 * ------------------------------------------------------------------------------------------------ */

enum { WRIST_ARTICULATED = 0, WRIST_STANFORD = 1, MAX_PRE_ROWS = 8, WRIST_HEADER = 39 };

typedef struct {
    int kind, standard, n_pre;
    double centre[3];          /* the wrist centre in the tool frame */
    double P[9], post[9];      /* W = P^T R_pre^T R post^T = Rz(a) Ry(b) Rz(c) */
    double s5, s6, offset[3];
    double arm[10];            /* articulated: u0 w0 sigma a2 o2 L phi s3 near far; Stanford: d1 d2 stroke_offset */
    double ca[MAX_PRE_ROWS], sa[MAX_PRE_ROWS], theta[MAX_PRE_ROWS]; /* the rows before the wrist */
    int joint[MAX_PRE_ROWS];   /* the revolute joint turning that row, or -1 */
} WristArm;

/* Python's float %: angle in (-pi, pi] as ur10core.branches.wrap and spherical_wrist._wrap1 write it. */
static double wrap_mod(double angle)
{
    double m = fmod(-angle + PI, TAU);
    if (m != 0.0) {
        if (m < 0.0) m += TAU;
    } else {
        m = 0.0;
    }
    return -m + PI;
}

/* The geometry array spherical_wrist.compiled_geometry() writes: 1, or 0 with an exception set. */
static int parse_wrist_arm(PyObject *obj, WristArm *G)
{
    if (!is_c_array(obj, NPY_DOUBLE)) {
        PyErr_SetString(PyExc_TypeError, "wrist_ik needs the geometry as a C-contiguous float64 array");
        return 0;
    }
    const double *g = (const double *)PyArray_DATA((PyArrayObject *)obj);
    const npy_intp size = PyArray_SIZE((PyArrayObject *)obj);
    if (size < WRIST_HEADER || g[2] < 0 || g[2] > MAX_PRE_ROWS || size != WRIST_HEADER + 4 * (npy_intp)g[2] ||
        (g[0] != WRIST_ARTICULATED && g[0] != WRIST_STANFORD)) {
        PyErr_SetString(PyExc_ValueError, "wrist_ik: the geometry array is not compiled_geometry()'s");
        return 0;
    }
    G->kind = (int)g[0];
    G->standard = g[1] != 0.0;
    G->n_pre = (int)g[2];
    memcpy(G->centre, g + 3, 3 * sizeof(double));
    memcpy(G->P, g + 6, 9 * sizeof(double));
    memcpy(G->post, g + 15, 9 * sizeof(double));
    G->s5 = g[24];
    G->s6 = g[25];
    memcpy(G->offset, g + 26, 3 * sizeof(double));
    memcpy(G->arm, g + 29, 10 * sizeof(double));
    for (int k = 0; k < G->n_pre; k++) {
        const double *row = g + WRIST_HEADER + 4 * k;
        G->ca[k] = row[0];
        G->sa[k] = row[1];
        G->theta[k] = row[2];
        G->joint[k] = (int)row[3];
        if (row[3] < -1 || row[3] > 2) {
            PyErr_SetString(PyExc_ValueError, "wrist_ik: a row before the wrist is turned by joint 1, 2 or 3 only");
            return 0;
        }
    }
    return 1;
}

static void matmul3(const double *A, const double *B, double *C) /* C = A B, row-major 3x3 */
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}

static void transpose3(const double *A, double *B)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) B[3 * j + i] = A[3 * i + j];
}

/* The rotation of the frame before the wrist's first row at joints 1-3 (DHTable.frames' product). */
static void rotation_before_wrist(const WristArm *G, const double *q3, double *R_pre)
{
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, link[9], next[9];
    for (int k = 0; k < G->n_pre; k++) {
        const double theta = G->theta[k] + (G->joint[k] >= 0 ? q3[G->joint[k]] : 0.0);
        const double ct = cos(theta), st = sin(theta), ca = G->ca[k], sa = G->sa[k];
        if (G->standard) { /* Rz(theta) Rx(alpha) */
            const double L[9] = {ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca};
            memcpy(link, L, sizeof L);
        } else {           /* Rx(alpha) Rz(theta) */
            const double L[9] = {ct, -st, 0.0, st * ca, ct * ca, -sa, st * sa, ct * sa, ca};
            memcpy(link, L, sizeof L);
        }
        matmul3(R, link, next);
        memcpy(R, next, sizeof R);
    }
    memcpy(R_pre, R, sizeof R);
}

/* Wrist.solve_one: joints 4-6 of slot `base` (not flipped) and base + 1 (flipped). */
static void wrist_joints(const WristArm *G, const double *R, double hint4, double arm_rounding, double *q,
                         npy_bool *valid, npy_bool *singular, int base)
{
    double R_pre[9], PT[9], RpreT[9], postT[9], A[9], B[9], W[9];
    rotation_before_wrist(G, q + 6 * base, R_pre);
    transpose3(G->P, PT);
    transpose3(R_pre, RpreT);
    transpose3(G->post, postT);
    matmul3(PT, RpreT, A);
    matmul3(A, R, B);
    matmul3(B, postT, W);
    const double sin_b = hypot(W[2], W[5]);
    /* _loose: the wrist singular, or theta4 fixed less well than LIMIT_TOLERANCE */
    const int loose = sin_b <= WRIST_TOLERANCE || sin_b * LIMIT_TOLERANCE <= SQUARE_ROUNDING + arm_rounding;
    const double row_hint = hint4 + G->offset[0];
    for (int flip = 0; flip < 2; flip++) {
        const double sign = (flip ? -1.0 : 1.0) * G->s5;
        const double b = atan2(sign * sin_b, W[8]);
        double a = atan2(sign * W[5], sign * W[2]);
        const double turn = fabs(wrap_mod(a - row_hint));
        int chosen_afar = 0;
        if (sin_b * turn <= WRIST_TURN_TOLERANCE) {
            chosen_afar = turn > LIMIT_TOLERANCE;
            a = row_hint;
        }
        const double ca = cos(a), sa = sin(a), cb = cos(b), sb = sin(b);
        const double c = atan2(-sa * W[0] + ca * W[3], cb * (ca * W[0] + sa * W[3]) - sb * W[6]);
        double *slot = q + 6 * (base + flip);
        for (int j = 0; j < 3; j++) slot[j] = q[6 * base + j];
        slot[3] = wrap_mod(a - G->offset[0]);
        slot[4] = wrap_mod(b * G->s5 - G->offset[1]);
        slot[5] = wrap_mod(c * G->s6 - G->offset[2]);
        valid[base + flip] = 1;
        singular[base + flip] = singular[base] || loose || chosen_afar;
    }
}

/* ArticulatedArm._solve_one's joints 1-3 (every even slot); the wrist centre c. */
static void articulated_arm(const WristArm *G, const double *c, const double *h, double *q, npy_bool *valid,
                            npy_bool *singular, npy_int8 *failure, double *detail)
{
    const double u0 = G->arm[0], w0 = G->arm[1], sigma = G->arm[2], a2 = G->arm[3], o2 = G->arm[4], L = G->arm[5],
                 phi = G->arm[6], s3 = G->arm[7], near = G->arm[8], far = G->arm[9];
    const double rho = hypot(c[0], c[1]);
    const double towards = atan2(c[1], c[0]);
    const double hint_beta = wrap_mod(s3 * h[2] + phi);
    const double hint_reach = sqrt(a2 * a2 + L * L + 2 * a2 * L * cos(hint_beta));
    for (int shoulder = 0; shoulder < 2; shoulder++) {
        double theta1 = wrap_mod(towards + shoulder * PI);
        if (rho * fabs(wrap_mod(theta1 - h[0])) <= CHOICE_TOLERANCE) theta1 = h[0];
        const double u = cos(theta1) * c[0] + sin(theta1) * c[1] - u0;
        const double w = sigma * c[2] - w0;
        const double r = hypot(u, w);
        const double cos_beta = (r * r - a2 * a2 - L * L) / (2 * a2 * L);
        const int too_far = r > far + LENGTH_TOLERANCE, too_close = r < near - LENGTH_TOLERANCE;
        for (int elbow = 0; elbow < 2; elbow++) {
            const int slot = 4 * shoulder + 2 * elbow;
            failure[slot] = failure[slot + 1] = too_far ? TOO_FAR_CODE : (too_close ? TOO_CLOSE_CODE : 0);
            detail[slot] = detail[slot + 1] = r;
            if (too_far || too_close) continue;
            const double sign = -sigma * (((elbow == 0) == (shoulder == 0)) ? 1.0 : -1.0);
            double beta = sign * acos(clamp_unit(cos_beta));
            const int same_side = sign * sin(hint_beta) >= 0 || fabs(sin(hint_beta)) <= SIDE_TOLERANCE;
            if (same_side && fabs(hint_reach - r) <= CHOICE_TOLERANCE) beta = hint_beta;
            const double x = a2 + L * cos(beta), y = L * sin(beta);
            const double theta2 = atan2(w, u) - atan2(y, x) - o2;
            q[6 * slot] = theta1;
            q[6 * slot + 1] = wrap_mod(theta2);
            q[6 * slot + 2] = wrap_mod((beta - phi) * s3);
            valid[slot] = 1;
            singular[slot] = rho <= LENGTH_TOLERANCE || fabs(sin(beta)) <= STRETCHED_TOLERANCE;
        }
    }
}

/* StanfordArm._solve_one's joints 1-3 (every even slot); the wrist centre c. */
static void stanford_arm(const WristArm *G, const double *c, const double *h, double *q, npy_bool *valid,
                         npy_bool *singular, npy_int8 *failure, double *detail, double *arm_rounding)
{
    const double d1 = G->arm[0], d2 = G->arm[1], stroke_offset = G->arm[2];
    const double x = c[0], y = c[1], z = c[2] - d1;
    const double rho = hypot(x, y);
    const int inside = rho < fabs(d2) - LENGTH_TOLERANCE;
    const double reach = sqrt(fmax(rho * rho - d2 * d2, 0.0));
    const double c1h = cos(h[0]), s1h = sin(h[0]);
    const double hint_u = c1h * x + s1h * y;
    const int hint_fits = fabs(-s1h * x + c1h * y - d2) <= CHOICE_TOLERANCE;
    for (int k = 0; k < 8; k++) {
        failure[k] = inside ? INSIDE_OFFSET_CODE : 0;
        detail[k] = rho;
    }
    if (inside) return;
    for (int shoulder = 0; shoulder < 2; shoulder++) {
        const double sign = shoulder == 0 ? 1.0 : -1.0;
        double theta1 = atan2(y, x) - atan2(d2, sign * reach);
        if (hint_fits && (sign * hint_u >= 0 || fabs(hint_u) <= SIDE_TOLERANCE)) theta1 = h[0];
        const double u = cos(theta1) * x + sin(theta1) * y;
        double stroke = hypot(u, z);
        if (stroke <= LENGTH_TOLERANCE) stroke = 0.0; /* WC on the shoulder, to the tolerance: θ2 free */
        /* singular where θ2 is fixed less well than LIMIT_TOLERANCE: the rounding of u over the stroke */
        const int loose2 = fabs(u) * stroke * LIMIT_TOLERANCE <= SQUARE_ROUNDING * rho * rho;
        /* _arm_rounding: how well theta1 and theta2 are fixed together */
        const double rounding = u != 0.0 && stroke != 0.0 ? SQUARE_ROUNDING * rho * (rho + stroke) / (fabs(u) * stroke)
                                                          : INFINITY;
        for (int reversed = 0; reversed < 2; reversed++) {
            const int slot = 4 * reversed + 2 * shoulder;
            double theta2 = atan2(u, z) + PI * reversed;
            if (stroke * fabs(wrap_mod(theta2 - h[1])) <= CHOICE_TOLERANCE) theta2 = h[1];
            q[6 * slot] = wrap_mod(theta1);
            q[6 * slot + 1] = wrap_mod(theta2);
            q[6 * slot + 2] = (reversed ? -stroke : stroke) - stroke_offset;
            valid[slot] = 1;
            singular[slot] = fabs(u) <= LENGTH_TOLERANCE || loose2;
            arm_rounding[slot] = rounding;
        }
    }
}

/* Every slot of one valid pose T (row-major 4x4); h: the hint's six joints. */
static void wrist_arm_pose(const WristArm *G, const double *T, const double *h, double *q, npy_bool *valid,
                           npy_bool *singular, npy_int8 *failure, double *detail)
{
    const double R[9] = {T[0], T[1], T[2], T[4], T[5], T[6], T[8], T[9], T[10]};
    double c[3];
    for (int i = 0; i < 3; i++)
        c[i] = T[4 * i + 3] + (R[3 * i] * G->centre[0] + R[3 * i + 1] * G->centre[1] + R[3 * i + 2] * G->centre[2]);
    double arm_rounding[8];
    for (int k = 0; k < 8; k++) {
        valid[k] = singular[k] = 0;
        arm_rounding[k] = 0.0;
        for (int j = 0; j < 6; j++) q[6 * k + j] = NAN;
    }
    if (G->kind == WRIST_ARTICULATED)
        articulated_arm(G, c, h, q, valid, singular, failure, detail);
    else
        stanford_arm(G, c, h, q, valid, singular, failure, detail, arm_rounding);
    for (int base = 0; base < 8; base += 2)
        if (valid[base]) wrist_joints(G, R, h[3], arm_rounding[base], q, valid, singular, base);
}

/* wrist_ik(T (n,4,4), hint (n,6) or None, geometry, q (n,8,6), valid, singular (n,8) bool, failure (n,8) int8,
 *          detail (n,8)) -> int: every slot of n poses without the GIL; the index of the first pose that is
 * not a valid transform (its outputs are not written; the caller raises), or -1. */
static PyObject *wrist_ik(PyObject *self, PyObject *args)
{
    PyObject *T_obj, *hint_obj, *geometry, *q, *valid, *singular, *failure, *detail;
    WristArm G;
    if (!check_configured()) return NULL;
    if (!PyArg_ParseTuple(args, "OOOOOOOO", &T_obj, &hint_obj, &geometry, &q, &valid, &singular, &failure, &detail))
        return NULL;
    if (!parse_wrist_arm(geometry, &G)) return NULL;
    const int hinted = hint_obj != Py_None;
    if (!is_c_array(T_obj, NPY_DOUBLE) || (hinted && !is_c_array(hint_obj, NPY_DOUBLE)) ||
        !is_c_array(q, NPY_DOUBLE) || !is_c_array(valid, NPY_BOOL) || !is_c_array(singular, NPY_BOOL) ||
        !is_c_array(failure, NPY_INT8) || !is_c_array(detail, NPY_DOUBLE)) {
        PyErr_SetString(PyExc_TypeError, "wrist_ik needs C-contiguous arrays of the documented dtypes");
        return NULL;
    }
    const npy_intp n = PyArray_SIZE((PyArrayObject *)T_obj) / 16;
    if (PyArray_SIZE((PyArrayObject *)T_obj) != 16 * n || (hinted && PyArray_SIZE((PyArrayObject *)hint_obj) != 6 * n) ||
        PyArray_SIZE((PyArrayObject *)q) != 48 * n || PyArray_SIZE((PyArrayObject *)valid) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)singular) != 8 * n || PyArray_SIZE((PyArrayObject *)failure) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)detail) != 8 * n) {
        PyErr_SetString(PyExc_ValueError, "wrist_ik: the hint's and outputs' sizes do not match the number of poses");
        return NULL;
    }
    const double *T = (const double *)PyArray_DATA((PyArrayObject *)T_obj);
    const double *hint = hinted ? (const double *)PyArray_DATA((PyArrayObject *)hint_obj) : NULL;
    double *q_data = (double *)PyArray_DATA((PyArrayObject *)q);
    npy_bool *valid_data = (npy_bool *)PyArray_DATA((PyArrayObject *)valid);
    npy_bool *singular_data = (npy_bool *)PyArray_DATA((PyArrayObject *)singular);
    npy_int8 *failure_data = (npy_int8 *)PyArray_DATA((PyArrayObject *)failure);
    double *detail_data = (double *)PyArray_DATA((PyArrayObject *)detail);
    static const double no_hint[6] = {0, 0, 0, 0, 0, 0};
    npy_intp first_bad = -1;

    Py_BEGIN_ALLOW_THREADS
    for (npy_intp m = 0; m < n; m++) {
        if (!pose_is_valid(T + 16 * m)) {
            if (first_bad < 0) first_bad = m;
            continue;
        }
        wrist_arm_pose(&G, T + 16 * m, hinted ? hint + 6 * m : no_hint, q_data + 48 * m, valid_data + 8 * m,
                       singular_data + 8 * m, failure_data + 8 * m, detail_data + 8 * m);
    }
    Py_END_ALLOW_THREADS

    return PyLong_FromSsize_t(first_bad);
}

static PyMethodDef methods[] = {
    {"set_tolerances", set_tolerances, METH_VARARGS, "Hand over ur10core/tolerances.py's values."},
    {"nearest_one", nearest_one, METH_VARARGS, "The valid IK slot nearest the current joints, shifted next to them."},
    {"frames", frames, METH_VARARGS, "Frames {0}..{6} of n joint vectors into a preallocated array."},
    {"jacobians", jacobians, METH_VARARGS, "Flange Jacobians of n joint vectors into a preallocated array."},
    {"jacobian_one", jacobian_one, METH_VARARGS, "The flange Jacobian of one joint vector."},
    {"quaternions", quaternions, METH_VARARGS, "Unit quaternions (w >= 0) of n rotation matrices."},
    {"fk_one", fk_one, METH_VARARGS, "Closed-form T06 of one joint vector."},
    {"ik_one", ik_one, METH_VARARGS, "IK of one validated-on-the-fly 4x4 pose (all eight slots)."},
    {"ik_batch", ik_batch, METH_VARARGS, "IK of n poses into preallocated outputs, without the GIL."},
    {"wrist_ik", wrist_ik, METH_VARARGS, "Every IK slot of n poses of a spherical-wrist arm, without the GIL."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernels",
                                    "ur10core's compiled kernel (see ur10core/ik_reference.py and ur10core/_numpy_kernels.py).", -1,
                                    methods};

PyMODINIT_FUNC PyInit__kernels(void)
{
    import_array();
    return PyModule_Create(&module);
}
