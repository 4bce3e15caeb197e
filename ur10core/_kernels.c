/*
 * Compiled IK kernel for ur10core: the same algorithm as ur10core/ik.py's readable
 * reference (`solve_reference`), line for line, so that one pose costs a couple of
 * microseconds and a batch runs without the GIL on several threads.
 *
 * COURSE_NOTES §4 (separation of variables, eight branches); slot k = 4 i + 2 j + l.
 * The tests check this kernel against the Python reference on many poses.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <math.h>

#define TAU (2.0 * M_PI)

/* Mirror ur10core/ik.py and ur10core/_validate.py. */
static double LENGTH_TOLERANCE = 1e-9;
static double WRIST_TOLERANCE = 1e-9;
static double ROTATION_TOLERANCE = 1e-6;
static double BOTTOM_ROW_TOLERANCE = 1e-9;

enum { REACHABLE = 0, WRIST_INSIDE_CYLINDER = 1, ELBOW_TOO_FAR = 2, ELBOW_TOO_CLOSE = 3 };

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

static inline double wrap(double x) /* into (-pi, pi]; x is within a few turns */
{
    while (x > M_PI) x -= TAU;
    while (x <= -M_PI) x += TAU;
    return x;
}

static inline double norm2(double x, double y) /* |(x, y)|: our values are O(1), no overflow */
{
    return sqrt(x * x + y * y);
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

static void solve_pose(const Params *P, const double *T, double theta6_hint, Out o)
{
    const double r11 = T[0], r12 = T[1], r13 = T[2], px = T[3];
    const double r21 = T[4], r22 = T[5], r23 = T[6], py = T[7];
    const double r31 = T[8], r32 = T[9], r33 = T[10], pz = T[11];
    const double d1 = P->d1, a2 = P->a2, a3 = P->a3, d4 = P->d4, d5 = P->d5, d6 = P->d6;

    /* Step 1: the wrist-2 point P5 = p - d6 z6 and its distance rho from the base axis. */
    const double p5x = px - d6 * r13, p5y = py - d6 * r23, p5z = pz - d6 * r33;
    const double rho2 = p5x * p5x + p5y * p5y;
    const double rho = sqrt(rho2);
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

    const double reach = rho2 > d4 * d4 ? sqrt(rho2 - d4 * d4) : 0.0;
    const double outer = a2 + a3, inner = fabs(a2 - a3);
    const double a2a3x2 = 2.0 * a2 * a3, a2sq_a3sq = a2 * a2 + a3 * a3;
    theta6_hint = wrap(theta6_hint);
    const double c6_hint = cos(theta6_hint), s6_hint = sin(theta6_hint);

    for (int i = 0; i < 2; i++) {
        const double A = i == 0 ? -reach : reach; /* signed reach of P5 along x1 */
        const double c1 = (p5x * A - p5y * d4) / rho2;
        const double s1 = (p5y * A + p5x * d4) / rho2;
        const double theta1 = wrap(atan2(s1, c1));
        /* Step 2: c5 = z4 . z6; |s5| from the row pair of step 3. */
        const double c5 = r13 * s1 - r23 * c1;
        const double c6s5 = r21 * c1 - r11 * s1;
        const double s6s5 = r12 * s1 - r22 * c1;
        const double s5_abs = norm2(c6s5, s6s5);
        const double c234s5 = r13 * c1 + r23 * s1;
        const int singular_wrist = s5_abs < WRIST_TOLERANCE;
        const double theta5_up = atan2(s5_abs, c5); /* in [0, pi] */
        double c6_up, s6_up, theta6_up;
        if (singular_wrist) { /* only theta234 +- theta6 is determined: keep the hint's theta6 */
            c6_up = c6_hint;
            s6_up = s6_hint;
            theta6_up = theta6_hint;
        } else { /* Step 3 */
            c6_up = c6s5 / s5_abs;
            s6_up = s6s5 / s5_abs;
            theta6_up = wrap(atan2(s6_up, c6_up));
        }
        double c234_up = 0.0, s234_up = 0.0, theta234_up = 0.0;
        for (int j = 0; j < 2; j++) {
            /* The j = 1 branch negates s5 and, away from the wrist singularity, turns theta6
             * by pi (negating c6, s6): the same angles the reference computes per branch. */
            const double sign = j == 0 ? 1.0 : -1.0;
            const double s5 = sign * s5_abs;
            const double theta5 = j == 0 ? theta5_up : wrap(-theta5_up);
            const double c6 = singular_wrist ? c6_up : sign * c6_up;
            const double s6 = singular_wrist ? s6_up : sign * s6_up;
            const double theta6 = (j == 0 || singular_wrist) ? theta6_up : wrap(theta6_up + M_PI);
            /* Step 4, blended with the third row so it holds at every theta5. Away from the
             * wrist singularity the j = 1 branch negates c234 and s234: theta234 + pi. */
            double c234, s234, theta234;
            if (j == 1 && !singular_wrist) {
                c234 = -c234_up;
                s234 = -s234_up;
                theta234 = theta234_up > 0.0 ? theta234_up - M_PI : theta234_up + M_PI;
            } else {
                c234 = s5 * c234s5 + c5 * c5 * (s6 * r31 + c6 * r32);
                s234 = s5 * r33 + c5 * (c6 * r31 - s6 * r32);
                const double norm = norm2(c234, s234);
                c234 /= norm;
                s234 /= norm;
                theta234 = atan2(s234, c234);
                if (j == 0) {
                    c234_up = c234;
                    s234_up = s234;
                    theta234_up = theta234;
                }
            }
            /* Step 5: the planar 2R problem for the frame-4 origin. */
            const double h4 = A + d5 * s234;
            const double v4 = p5z - d1 - d5 * c234;
            const double r = norm2(h4, v4);
            const int base = 4 * i + 2 * j;
            o.elbow_distance[base] = o.elbow_distance[base + 1] = r;
            if (!(r <= outer + LENGTH_TOLERANCE)) { /* NaN too: a target so far that r overflowed */
                o.failure[base] = o.failure[base + 1] = ELBOW_TOO_FAR;
                continue;
            }
            if (r < inner - LENGTH_TOLERANCE) {
                o.failure[base] = o.failure[base + 1] = ELBOW_TOO_CLOSE;
                continue;
            }
            const int at_limit = r >= outer - LENGTH_TOLERANCE || r <= inner + LENGTH_TOLERANCE;
            double c3 = (r * r - a2sq_a3sq) / a2a3x2;
            c3 = c3 > 1.0 ? 1.0 : (c3 < -1.0 ? -1.0 : c3);
            const double s3 = sqrt(1.0 - c3 * c3);
            const double theta3 = atan2(s3, c3);
            const double beta = atan2(v4, h4);
            const double gamma = atan2(a3 * s3, a2 + a3 * c3);
            for (int l = 0; l < 2; l++) {
                const int k = base + l;
                const double t3 = l == 0 ? theta3 : wrap(-theta3);
                const double t2 = wrap(l == 0 ? beta - gamma : beta + gamma);
                double *qk = o.q + 6 * k;
                qk[0] = theta1;
                qk[1] = t2;
                qk[2] = t3;
                qk[3] = wrap(theta234 - t2 - t3);
                qk[4] = theta5;
                qk[5] = theta6;
                o.valid[k] = 1;
                o.wrist[k] = (npy_bool)singular_wrist;
                o.elbow[k] = (npy_bool)at_limit;
                o.failure[k] = REACHABLE;
            }
        }
    }
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

/* ik_one(T, theta6_hint, params) -> tuple of arrays, or None when T is not a valid pose.
 * T must be a C-contiguous float64 (4, 4) array (the caller guarantees it). */
static PyObject *ik_one(PyObject *self, PyObject *args)
{
    PyObject *T_obj, *params;
    double hint;
    Params P;
    if (!PyArg_ParseTuple(args, "OdO", &T_obj, &hint, &params)) return NULL;
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
    solve_pose(&P, T, hint, o);
    return Py_BuildValue("(NNNNNNNN)", q, valid, wrist, elbow, shoulder, failure, rho, distance);
}

/* ik_batch(T (n,4,4), hint (n,), params, q (n,8,6), valid, wrist, elbow (n,8) bool,
 *          shoulder (n,) bool, failure (n,8) int8, rho (n,), distance (n,8)) -> int
 * Solves every pose without the GIL; returns the index of the first pose that is not
 * a valid transform (the caller raises; such a pose's outputs are not written), or -1. */
static PyObject *ik_batch(PyObject *self, PyObject *args)
{
    PyObject *T_obj, *hint_obj, *params, *q, *valid, *wrist, *elbow, *shoulder, *failure, *rho,
        *distance;
    Params P;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOO", &T_obj, &hint_obj, &params, &q, &valid, &wrist,
                          &elbow, &shoulder, &failure, &rho, &distance))
        return NULL;
    if (!parse_params(params, &P)) return NULL;
    if (!is_c_array(T_obj, NPY_DOUBLE) || !is_c_array(hint_obj, NPY_DOUBLE) ||
        !is_c_array(q, NPY_DOUBLE) || !is_c_array(valid, NPY_BOOL) ||
        !is_c_array(wrist, NPY_BOOL) || !is_c_array(elbow, NPY_BOOL) ||
        !is_c_array(shoulder, NPY_BOOL) || !is_c_array(failure, NPY_INT8) ||
        !is_c_array(rho, NPY_DOUBLE) || !is_c_array(distance, NPY_DOUBLE)) {
        PyErr_SetString(PyExc_TypeError, "ik_batch needs C-contiguous arrays of the documented dtypes");
        return NULL;
    }
    npy_intp n = PyArray_SIZE((PyArrayObject *)T_obj) / 16;
    if (PyArray_SIZE((PyArrayObject *)T_obj) != 16 * n || PyArray_SIZE((PyArrayObject *)hint_obj) != n ||
        PyArray_SIZE((PyArrayObject *)q) != 48 * n || PyArray_SIZE((PyArrayObject *)valid) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)wrist) != 8 * n || PyArray_SIZE((PyArrayObject *)elbow) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)shoulder) != n || PyArray_SIZE((PyArrayObject *)failure) != 8 * n ||
        PyArray_SIZE((PyArrayObject *)rho) != n || PyArray_SIZE((PyArrayObject *)distance) != 8 * n) {
        PyErr_SetString(PyExc_ValueError, "ik_batch: output sizes do not match the number of poses");
        return NULL;
    }
    const double *T = (const double *)PyArray_DATA((PyArrayObject *)T_obj);
    const double *hint = (const double *)PyArray_DATA((PyArrayObject *)hint_obj);
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
    for (npy_intp m = 0; m < n; m++) {
        const double *Tm = T + 16 * m;
        Out o = {q_data + 48 * m, valid_data + 8 * m, wrist_data + 8 * m, elbow_data + 8 * m,
                 failure_data + 8 * m, distance_data + 8 * m, rho_data + m, shoulder_data + m};
        if (!pose_is_valid(Tm)) {
            if (first_bad < 0) first_bad = m;
            continue;
        }
        solve_pose(&P, Tm, hint[m], o);
    }
    Py_END_ALLOW_THREADS

    return PyLong_FromSsize_t(first_bad);
}

/* fk_one(q, params) -> (4, 4) array T06 in closed form (COURSE_NOTES §3), or None if q is
 * not finite. q must be a C-contiguous float64 array of 6 joint angles. */
static PyObject *fk_one(PyObject *self, PyObject *args)
{
    PyObject *q_obj, *params;
    Params P;
    if (!PyArg_ParseTuple(args, "OO", &q_obj, &params)) return NULL;
    if (!parse_params(params, &P)) return NULL;
    if (!is_c_array(q_obj, NPY_DOUBLE) || PyArray_SIZE((PyArrayObject *)q_obj) != 6) {
        PyErr_SetString(PyExc_TypeError, "fk_one needs a C-contiguous float64 array of 6 angles");
        return NULL;
    }
    const double *q = (const double *)PyArray_DATA((PyArrayObject *)q_obj);
    for (int k = 0; k < 6; k++)
        if (!isfinite(q[k])) Py_RETURN_NONE;
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

/* frames(q (n, 6), params, out (n, 7, 4, 4)): T0i = T01 T12 ... T(i-1,i) of the course's
 * modified DH table (COURSE_NOTES §2), every joint vector; ur10core.arm.Arm.frames. */
static PyObject *frames(PyObject *self, PyObject *args)
{
    PyObject *q_obj, *params, *out_obj;
    Params P;
    if (!PyArg_ParseTuple(args, "OOO", &q_obj, &params, &out_obj)) return NULL;
    if (!parse_params(params, &P)) return NULL;
    if (!is_c_array(q_obj, NPY_DOUBLE) || !is_c_array(out_obj, NPY_DOUBLE)) {
        PyErr_SetString(PyExc_TypeError, "frames needs C-contiguous float64 arrays");
        return NULL;
    }
    const npy_intp n = PyArray_SIZE((PyArrayObject *)q_obj) / 6;
    if (PyArray_SIZE((PyArrayObject *)q_obj) != 6 * n || PyArray_SIZE((PyArrayObject *)out_obj) != 112 * n) {
        PyErr_SetString(PyExc_ValueError, "frames: q must hold n x 6 angles and out n x 7 x 4 x 4");
        return NULL;
    }
    const double *q = (const double *)PyArray_DATA((PyArrayObject *)q_obj);
    double *out = (double *)PyArray_DATA((PyArrayObject *)out_obj);
    /* alpha_{i-1}: 0, +pi/2, 0, 0, -pi/2, +pi/2 as (cos, sin); a_{i-1}; d_i */
    const double ca[6] = {1.0, 0.0, 1.0, 1.0, 0.0, 0.0}, sa[6] = {0.0, 1.0, 0.0, 0.0, -1.0, 1.0};
    const double a[6] = {0.0, 0.0, P.a2, P.a3, 0.0, 0.0}, d[6] = {P.d1, 0.0, 0.0, P.d4, P.d5, P.d6};
    Py_BEGIN_ALLOW_THREADS
    for (npy_intp m = 0; m < n; m++) {
        double *F = out + 112 * m;
        for (int k = 0; k < 16; k++) F[k] = (k % 5 == 0) ? 1.0 : 0.0; /* frame {0} = I */
        for (int i = 0; i < 6; i++) {
            const double ct = cos(q[6 * m + i]), st = sin(q[6 * m + i]);
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
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
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
 * 2pi-equivalent nearest the current one (one turn back where that leaves +-joint_limit),
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
            if (v > limit) v -= TAU;
            if (v < -limit) v += TAU;
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

static PyMethodDef methods[] = {
    {"nearest_one", nearest_one, METH_VARARGS, "The valid IK slot nearest the current joints, shifted next to them."},
    {"frames", frames, METH_VARARGS, "Frames {0}..{6} of n joint vectors into a preallocated array."},
    {"quaternions", quaternions, METH_VARARGS, "Unit quaternions (w >= 0) of n rotation matrices."},
    {"fk_one", fk_one, METH_VARARGS, "Closed-form T06 of one joint vector."},
    {"ik_one", ik_one, METH_VARARGS, "IK of one validated-on-the-fly 4x4 pose (all eight slots)."},
    {"ik_batch", ik_batch, METH_VARARGS, "IK of n poses into preallocated outputs, without the GIL."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernels",
                                    "Compiled IK kernel of ur10core (see ur10core/ik.py).", -1,
                                    methods};

PyMODINIT_FUNC PyInit__kernels(void)
{
    import_array();
    return PyModule_Create(&module);
}
