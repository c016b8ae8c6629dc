/* catenary_monitor.core.physics._fused_kernel: problems 3 and 4 (hook tension given) with their margins, in C.
 *
 * The same formulas as catenary.py (grounded, _uplift_setup, _uplift_residual, _lifted_from_d,
 * critical_parameter) fused into one pass over blocks of BLK lanes, so that no intermediate leaves
 * the L1 cache, and vectorized by GCC with glibc's vector math library (libmvec): every loop over
 * lanes is straight-line code with selects.  The block function is compiled three times
 * (x86-64-v4 with 512-bit vectors, x86-64-v3, and the baseline) and the best one the CPU runs is
 * picked at import.  One code path serves one element (solve_one, the live node's case) and
 * arrays (solve_tension).  Python keeps the numpy implementation as the reference and fallback
 * (catenary_monitor.core.physics.fused_kernel). */

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#ifndef _WIN32
#include <pthread.h>
#define CM_THREADS 1
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__GLIBC__)
#define CM_MVEC 1
/* glibc declares its vector variants only under -ffast-math; declare them ourselves. */
#pragma omp declare simd notinbranch
double exp(double);
#pragma omp declare simd notinbranch
double expm1(double);
#pragma omp declare simd notinbranch
double log(double);
#pragma omp declare simd notinbranch
double log1p(double);
#pragma omp declare simd notinbranch
double atan2(double, double);
#endif

#define BLK 256
#define KFAST 6 /* Newton steps on whole blocks before the bracketed per-lane loop */
/* m = x/B below this: the block's fast steps and state would under- or overflow (m^2, m^4), so
 * the lane is solved by the scaled per-lane code (uplift_tiny) */
#define TINY_M 0x1p-200
#define NOUT 12
#define LOG_2 0.69314718055994530942
#define RAD2DEG (180.0 / 3.14159265358979323846)

/* result rows, in catenary_monitor.core.physics.result.ALL_KEYS order */
enum { O_R, O_T, O_XMIN, O_L, O_BETA, O_ALPHA, O_F, O_AM, O_TIDE, O_LOAD, O_GL, O_SF };
/* catenary_monitor.core.physics.result.Status */
enum {
    ST_NON_FINITE = 1,
    ST_WEIGHT = 2,
    ST_DEPTH = 3,
    ST_TENSION = 4,
    ST_DISTANCE = 6,
    ST_MBL = 9,
    ST_NO_CONVERGENCE = 10,
    ST_OUT_OF_RANGE = 13
};

typedef struct {
    int has_x, has_mbl, maxiter;
    double step_tol;
} Params;

/* the lanes of one block; Block1 (one lane, the node's call) keeps its few cache lines together */
#define DEFINE_BLOCK(NAME, N)                                                                   \
    typedef struct {                                                                           \
        double w[N], h[N], t[N], x[N];                                                             \
        double b[N], e[N], r02[N], len[N], x0[N];                                              \
        double xlo[N], m[N], d[N], d0[N], d_max[N];                                            \
        int status[N], lift[N], iters[N], cok[N], ldone[N];                                    \
        /* the lifted lanes, gathered */                                                       \
        int idx[N], gdone[N], giters[N];                                                       \
        double ge[N], gr[N], gx0[N], gxlo[N], gm[N], gd[N], gd0[N], gdmax[N];                  \
        double *o[NOUT]; /* where this block's results go (rows of the output) */              \
        const double *src[5]; /* the inputs w, h, t, x, mbl of this block (read in place) */   \
        double cin[5][N]; /* a constant input's lanes; a last, partial block's padded copy */  \
        double spill[NOUT][N]; /* the results of a last, partial block (padded lanes) */     \
    } NAME;
DEFINE_BLOCK(Block, BLK)
DEFINE_BLOCK(Block1, 1)

/* the load-margin start table (catenary._CRIT_*), handed over by Python at import */
static struct {
    double *data; /* eta[0], slope[0], eta[1], slope[1], ...: one cache line per lookup */
    int n;
    double y0, inv_dy;
} TAB = {NULL, 0, 0.0, 0.0};

/* exact error of the product w*h - p (Dekker/Veltkamp split, as catenary.two_prod_diff) */
static inline __attribute__((always_inline)) double prod_err(double w, double h, double p)
{
    const double split = 134217729.0;
    double cw = split * w, wh = cw - (cw - w), wl = w - wh;
    double ch = split * h, hh = ch - (ch - h), hl = h - hh;
    return ((wh * hh - p) + wh * hl + wl * hh) + wl * hl;
}

/* catenary.critical_parameter_scalar: a of the no-uplift chain spanning (x, h); NaN if not
 * converged within maxiter residuals */
static double critical_scalar(double h, double x, const Params *par)
{
    double c = h / x, log_c = log(c), eta;
    double pos = (log_c - TAB.y0) * TAB.inv_dy;
    if (pos >= 0.0 && pos < TAB.n) {
        int j = (int)pos;
        const double *tj = TAB.data + 2 * j;
        double tt = pos - j, y0 = tj[0], s0 = tj[1], y1 = tj[2], s1 = tj[3];
        eta = y0 + tt * (s0 + tt * ((3.0 * (y1 - y0) - 2.0 * s0 - s1) +
                                    tt * (2.0 * (y0 - y1) + s0 + s1)));
    } else if (c < 0.5) {
        double c2 = c * c;
        eta = log(c * (1.0 - c2 * (1.0 / 3.0 - c2 * (13.0 / 45.0))));
    } else {
        double big = log(4.0 * c);
        double half = 0.5 * big;
        eta = log(0.5 * (big + log(half > 1.0 ? half : 1.0)));
    }
    for (int it = 0; it < par->maxiter; it++) {
        double d = exp(eta);
        double f = 2.0 * (d + log(-expm1(-2.0 * d)) - LOG_2) - eta - log_c;
        double step = -f / (2.0 * d / tanh(d) - 1.0);
        step = step > 4.0 ? 4.0 : (step < -4.0 ? -4.0 : step);
        eta += step;
        if (fabs(step) <= par->step_tol)
            return x / (2.0 * exp(eta));
    }
    return NAN;
}

#define CM_PRAGMA(x) _Pragma(#x)
#define CM_SIMD CM_PRAGMA(omp simd)
#define CM_SIMD_REDUCTION(...) CM_PRAGMA(omp simd reduction(+ : __VA_ARGS__))
#define CM_SIMD_WITH(clauses) CM_PRAGMA(omp simd clauses)
#ifdef CM_MVEC
#define BLOCK_T Block
/* Every vector loop runs over a multiple of 16 lanes (stand-in lanes fill the rest: AVX-512
 * runs the loops that mix int and double lanes 16 at a time), so that no element is ever left
 * to a loop's scalar remainder: each element takes the same vector code
 * (libmvec) wherever it falls in its block, and a replay cut into windows gives the very bits
 * of the whole log at once (test/test_replay_stream.py). */
#define PADDED(n) (((n) + 15) / 16 * 16)
#define LANES(n) PADDED(n)
#define SFX(name) name##_v4
#pragma GCC push_options
#pragma GCC target("arch=x86-64-v4,prefer-vector-width=512")
#include "_fused_kernel_body.h"
#pragma GCC pop_options
#undef SFX
#define SFX(name) name##_v3
#pragma GCC push_options
#pragma GCC target("arch=x86-64-v3")
#include "_fused_kernel_body.h"
#pragma GCC pop_options
#undef SFX
#endif
#define SFX(name) name##_base
#include "_fused_kernel_body.h"
#undef SFX
/* one element (solve_one): the same code without vectors, calling the scalar libm */
#undef CM_SIMD
#undef CM_SIMD_REDUCTION
#define CM_SIMD
#define CM_SIMD_REDUCTION(...)
#undef CM_SIMD_WITH
#define CM_SIMD_WITH(clauses)
#pragma GCC push_options
#pragma GCC optimize("no-tree-vectorize")
#undef BLOCK_T
#define BLOCK_T Block1
#undef LANES
#define LANES(n) (n)
#define SFX(name) name##_scalar
#include "_fused_kernel_body.h"
#undef SFX
#pragma GCC pop_options

typedef void (*block_fn)(Block *restrict, int, const Params *restrict);
static block_fn BLOCK_FN = block_base;
static const char *ISA = "baseline";

/* ---------------------------------------------------------------- Python interface */

static PyTypeObject *RESULT_TYPE = NULL;
static PyObject *RESULT_TAILS = NULL;
static PyObject *NAN_OBJ = NULL; /* one NaN float shared by every result */

static inline PyObject *value(double v)
{
    if (v != v && NAN_OBJ) {
        Py_INCREF(NAN_OBJ);
        return NAN_OBJ;
    }
    return PyFloat_FromDouble(v);
}

typedef struct {
    Py_buffer view;
    const double *p; /* NULL: constant */
    double c;
    int given, held;
} In;

static int in_from(PyObject *o, In *in, Py_ssize_t *n, const char *name)
{
    memset(in, 0, sizeof(*in));
    in->c = 1.0;
    if (o == Py_None)
        return 0;
    in->given = 1;
    if (PyFloat_CheckExact(o)) {
        in->c = PyFloat_AS_DOUBLE(o);
        return 0;
    }
    if (PyObject_GetBuffer(o, &in->view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return -1;
    in->held = 1;
    if (in->view.itemsize != 8 || !in->view.format || strcmp(in->view.format, "d") != 0) {
        PyErr_Format(PyExc_TypeError, "%s: a float64 array or a float is needed", name);
        return -1;
    }
    Py_ssize_t len = in->view.len / 8;
    if (*n < 0)
        *n = len;
    else if (*n != len) {
        PyErr_Format(PyExc_ValueError, "%s: length %zd, expected %zd", name, len, *n);
        return -1;
    }
    in->p = (const double *)in->view.buf;
    return 0;
}

static void in_release(In *in)
{
    if (in->held)
        PyBuffer_Release(&in->view);
}

static int params_from(PyObject *maxiter, PyObject *tol, Params *par)
{
    par->maxiter = (int)PyLong_AsLong(maxiter);
    par->step_tol = PyFloat_AsDouble(tol);
    return PyErr_Occurred() ? -1 : 0;
}

/* row[r]: where result row r goes (n doubles), or NULL: a row nobody asked for, computed into
 * the block's spill and dropped (no memory of the caller's written for it) */
#if defined(__x86_64__) && defined(__SSE2__)
#include <emmintrin.h>
/* nb doubles to dst with non-temporal stores (no read of the destination's lines first) */
static void stream_row(double *dst, const double *src, int nb)
{
    int i = 0;
    if (((uintptr_t)dst & 15) && nb > 0) {
        dst[0] = src[0];
        i = 1;
    }
    for (; i + 2 <= nb; i += 2)
        _mm_stream_pd(dst + i, _mm_loadu_pd(src + i));
    for (; i < nb; i++)
        dst[i] = src[i];
}
#define CM_STREAM 1
#endif

/* results at least this large bypass the cache on their way out, as glibc's memcpy does with
 * copies of this order: they would not stay in it anyway, and a plain store first reads every
 * line it writes */
#define STREAM_BYTES ((Py_ssize_t)32 << 20)

/* one share of a call: elements [lo, hi); row[r]: where result row r goes (n doubles), or
 * NULL: a row nobody asked for, computed into the block's spill and dropped (no memory of the
 * caller's written for it) */
typedef struct {
    In *in;
    const Params *par;
    Py_ssize_t lo, hi;
    double **row;
    long long *status, *iters;
    int stream, ok;
} Share;

/* one share of a call (elements [lo, hi), lo a multiple of BLK) in its own block scratch */
static void run_share(Share *sh)
{
    const Params *par = sh->par;
    In *in = sh->in;
    double **row = sh->row;
    long long *status = sh->status, *iters = sh->iters;
    const Py_ssize_t n = sh->hi;
    const int stream = sh->stream;
    Block *k = PyMem_RawMalloc(sizeof(Block));
    sh->ok = k != NULL;
    if (!k)
        return;
    for (int j = 0; j < 5; j++) /* a constant input: its lanes once for the whole call */
        if (!in[j].p)
            for (int i = 0; i < BLK; i++)
                k->cin[j][i] = in[j].c;
    for (Py_ssize_t off = sh->lo; off < n; off += BLK) {
        int nb = (int)(n - off < BLK ? n - off : BLK);
        int np = PADDED(nb);
        for (int j = 0; j < 5; j++) {
            if (!in[j].p) {
                k->src[j] = k->cin[j];
                continue;
            }
            if (np == nb) { /* whole vectors: read the input in place */
                k->src[j] = in[j].p + off;
                continue;
            }
            /* a last, partial block: copied, then stand-ins (copies of its first element) */
            memcpy(k->cin[j], in[j].p + off, (size_t)nb * sizeof(double));
            for (int i = nb; i < np; i++)
                k->cin[j][i] = k->cin[j][0];
            k->src[j] = k->cin[j];
        }
        int direct = np == nb && !stream; /* the block writes its rows in place */
        for (int r = 0; r < NOUT; r++)
            k->o[r] = direct && row[r] ? row[r] + off : k->spill[r];
        BLOCK_FN(k, np, par);
        long long *restrict so = status + off;
        const int *restrict sk = k->status;
        int bad = 0;
        CM_SIMD_REDUCTION(bad)
        for (int i = 0; i < nb; i++) {
            so[i] = sk[i];
            bad += sk[i] != 0;
        }
        if (bad) /* rare: the invalid elements' rows become NaN */
            for (int i = 0; i < nb; i++)
                if (sk[i])
                    for (int r = 0; r < NOUT; r++)
                        k->o[r][i] = NAN;
        if (!direct)
            for (int r = 0; r < NOUT; r++) {
                if (!row[r])
                    continue;
#ifdef CM_STREAM
                if (stream) {
                    stream_row(row[r] + off, k->spill[r], nb);
                    continue;
                }
#endif
                memcpy(row[r] + off, k->spill[r], (size_t)nb * sizeof(double));
            }
        if (iters) {
            long long *restrict io = iters + off;
            const int *restrict ik = k->iters;
            CM_SIMD
            for (int i = 0; i < nb; i++)
                io[i] = ik[i];
        }
    }
#ifdef CM_STREAM
    if (stream)
        _mm_sfence();
#endif
    PyMem_RawFree(k);
}

#ifdef CM_THREADS
static void *share_main(void *arg)
{
    run_share((Share *)arg);
    return NULL;
}
#endif

/* the threads solve_tension may use (set_threads) and the elements each must have at least:
 * below that, starting a thread (~20-50 us) costs more than it saves */
#define MAX_THREADS 64
#define MIN_SHARE (8 * BLK)
static int THREADS = 1;

/* the whole call: cut into at most THREADS shares of whole blocks, one per thread (the calling
 * thread takes the first); every element takes the same code whatever its share, so the
 * results do not depend on the thread count.  Returns 0 when memory ran out. */
static int run(In in[5], const Params *par, Py_ssize_t n, double *row[NOUT], long long *status,
               long long *iters)
{
    int nrow = 0;
    for (int r = 0; r < NOUT; r++)
        nrow += row[r] != NULL;
#ifdef CM_STREAM
    const int stream = (Py_ssize_t)nrow * n * (Py_ssize_t)sizeof(double) >= STREAM_BYTES;
#else
    const int stream = 0;
#endif
    Py_ssize_t nblk = (n + BLK - 1) / BLK;
    /* the calling thread starts the others one after the other (~20 us each) while a share
     * takes ~40 ns per element: nt threads pay while n / nt * 40 ns >= nt * 20 us, that is
     * nt <= sqrt(n / 512) (2 threads from 4096 elements, 14 at 1e5, 44 at 1e6) */
    Py_ssize_t nt = n / MIN_SHARE < THREADS ? n / MIN_SHARE : THREADS;
    Py_ssize_t paying = (Py_ssize_t)sqrt((double)n / 512.0);
    nt = nt < paying ? nt : paying;
    if (nt < 1)
        nt = 1;
    Share sh[MAX_THREADS];
    int started[MAX_THREADS] = {0};
    for (Py_ssize_t t = 0; t < nt; t++) {
        Py_ssize_t lo = nblk * t / nt * BLK, hi = nblk * (t + 1) / nt * BLK;
        sh[t] = (Share){in, par, lo, hi < n ? hi : n, row, status, iters, stream, 0};
    }
#ifdef CM_THREADS
    pthread_t tid[MAX_THREADS];
    for (Py_ssize_t t = 1; t < nt; t++)
        started[t] = pthread_create(&tid[t], NULL, share_main, &sh[t]) == 0;
#endif
    run_share(&sh[0]);
    int ok = sh[0].ok;
    for (Py_ssize_t t = 1; t < nt; t++) {
#ifdef CM_THREADS
        if (started[t])
            pthread_join(tid[t], NULL);
#endif
        if (!started[t])
            run_share(&sh[t]); /* no thread to be had: this one does the share */
        ok &= sh[t].ok;
    }
    return ok;
}

/* solve_tension(w, h, t, x, mbl, out, status, iters, maxiter, step_tol[, rows]) -> None
 * w, h, t: float or float64 arrays of one length n; x, mbl: the same or None; out: writable
 * float64 buffer of NOUT * n (rows in ALL_KEYS order); status, iters: int64 buffers of n
 * (iters may be None: the uplift residuals evaluated per element).  rows (an int, bit r for
 * row r; default all): only those rows are written, into out of popcount(rows) * n, in
 * ALL_KEYS order. */
static PyObject *solve_tension(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 10 && nargs != 11) {
        PyErr_SetString(PyExc_TypeError, "solve_tension takes 10 or 11 arguments");
        return NULL;
    }
    long mask = (1L << NOUT) - 1;
    if (nargs == 11) {
        mask = PyLong_AsLong(args[10]);
        if (mask == -1 && PyErr_Occurred())
            return NULL;
        if (mask < 0 || mask >= (1L << NOUT)) {
            PyErr_SetString(PyExc_ValueError, "rows: a mask of the 12 result rows");
            return NULL;
        }
    }
    int nrow = 0;
    for (int r = 0; r < NOUT; r++)
        nrow += (mask >> r) & 1;
    if (!TAB.n) {
        PyErr_SetString(PyExc_RuntimeError, "load-margin table not set");
        return NULL;
    }
    static const char *names[5] = {"weight", "depth", "tension", "anchor_distance", "mbl"};
    In in[5];
    Py_buffer ob = {0}, sb = {0}, ib = {0};
    int have_o = 0, have_s = 0, have_i = 0, ok = 0;
    Py_ssize_t n = -1;
    Params par;
    memset(in, 0, sizeof(in));
    for (int j = 0; j < 5; j++)
        if (in_from(args[j], &in[j], &n, names[j]) < 0)
            goto done;
    if (n < 0)
        n = 1;
    if (params_from(args[8], args[9], &par) < 0)
        goto done;
    par.has_x = in[3].given;
    par.has_mbl = in[4].given;
    if (PyObject_GetBuffer(args[5], &ob, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        goto done;
    have_o = 1;
    if (PyObject_GetBuffer(args[6], &sb, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        goto done;
    have_s = 1;
    if (args[7] != Py_None) {
        if (PyObject_GetBuffer(args[7], &ib, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
            goto done;
        have_i = 1;
    }
    if (ob.len != (Py_ssize_t)(nrow * n * 8) || sb.len != n * 8 || (have_i && ib.len != n * 8)) {
        PyErr_SetString(PyExc_ValueError, "output buffers of the wrong size");
        goto done;
    }
    double *row[NOUT];
    for (int r = 0, q = 0; r < NOUT; r++)
        row[r] = (mask >> r) & 1 ? (double *)ob.buf + (Py_ssize_t)(q++) * n : NULL;
    int ran;
    Py_BEGIN_ALLOW_THREADS;
    ran = run(in, &par, n, row, (long long *)sb.buf, have_i ? (long long *)ib.buf : NULL);
    Py_END_ALLOW_THREADS;
    if (!ran) {
        PyErr_NoMemory();
        goto done;
    }
    ok = 1;
done:
    for (int j = 0; j < 5; j++)
        in_release(&in[j]);
    if (have_o)
        PyBuffer_Release(&ob);
    if (have_s)
        PyBuffer_Release(&sb);
    if (have_i)
        PyBuffer_Release(&ib);
    if (!ok)
        return NULL;
    Py_RETURN_NONE;
}

static double ONE_TOL = 1e-9; /* STEP_TOL for solve_one, set with set_result */

/* a plain number for the one-element path: float (or a subclass, numpy.float64) or int */
static inline int plain(PyObject *o) { return PyFloat_Check(o) || PyLong_CheckExact(o); }

/* solve_one(w, h, t, horizontal, x, chain_length, mbl, ea, maxiter)
 * -> the registered result (set_result), else (12 floats in ALL_KEYS order, status);
 * None when the call is not one element of problem 3 or 4 in plain numbers (then
 * catenary_monitor.solve takes its general path).  The argument order is solve()'s. */
static PyObject *solve_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 9) {
        PyErr_SetString(PyExc_TypeError, "solve_one takes 9 arguments");
        return NULL;
    }
    PyObject *x_o = args[4], *mbl_o = args[6];
    if (args[3] != Py_None || args[5] != Py_None || args[7] != Py_None || !plain(args[0]) ||
        !plain(args[1]) || !plain(args[2]) || (x_o != Py_None && !plain(x_o)) ||
        (mbl_o != Py_None && !plain(mbl_o)) || !TAB.n)
        Py_RETURN_NONE;
    PyObject *in_o[5] = {args[0], args[1], args[2], x_o, mbl_o};
    double v[5];
    Params par;
    par.has_x = x_o != Py_None;
    par.has_mbl = mbl_o != Py_None;
    for (int j = 0; j < 5; j++) {
        v[j] = in_o[j] == Py_None ? 1.0 : PyFloat_AsDouble(in_o[j]);
        if (v[j] == -1.0 && PyErr_Occurred())
            return NULL;
    }
    par.maxiter = (int)PyLong_AsLong(args[8]);
    if (par.maxiter == -1 && PyErr_Occurred())
        return NULL;
    par.step_tol = ONE_TOL;
    /* one lane: a small block on the stack's worth of heap, reused between calls */
    static Block1 one;
    Block1 *k = &one;
    for (int j = 0; j < 5; j++) {
        k->cin[j][0] = v[j];
        k->src[j] = k->cin[j];
    }
    double o[NOUT];
    for (int r = 0; r < NOUT; r++)
        k->o[r] = o + r;
    block_scalar(k, 1, &par);
    int st = k->status[0];
    int tail = 2 * par.has_x + par.has_mbl;
    if (RESULT_TYPE) { /* build the SolveResult itself: 12 values, status, then the tail */
        PyObject *tl = PyTuple_GET_ITEM(RESULT_TAILS, tail);
        Py_ssize_t nt = PyTuple_GET_SIZE(tl);
        PyObject *res = RESULT_TYPE->tp_alloc(RESULT_TYPE, NOUT + 1 + nt);
        if (!res)
            return NULL;
        for (int r = 0; r < NOUT; r++)
            PyTuple_SET_ITEM(res, r, value(st ? NAN : o[r]));
        PyTuple_SET_ITEM(res, NOUT, PyLong_FromLong(st));
        for (Py_ssize_t j = 0; j < nt; j++) {
            PyObject *item = PyTuple_GET_ITEM(tl, j);
            Py_INCREF(item);
            PyTuple_SET_ITEM(res, NOUT + 1 + j, item);
        }
        return res;
    }
    PyObject *res = PyTuple_New(NOUT + 1);
    if (!res)
        return NULL;
    for (int r = 0; r < NOUT; r++)
        PyTuple_SET_ITEM(res, r, value(st ? NAN : o[r]));
    PyTuple_SET_ITEM(res, NOUT, PyLong_FromLong(st));
    return res;
}

/* set_result(cls, tails, step_tol): solve_one returns cls(12 values, status, *tails[2 has_x + has_mbl])
 * (cls a tuple subclass without instance fields: the SolveResult named tuple) */
static PyObject *set_result(PyObject *self, PyObject *args)
{
    PyObject *cls, *tails;
    double tol;
    if (!PyArg_ParseTuple(args, "O!O!d", &PyType_Type, &cls, &PyTuple_Type, &tails, &tol))
        return NULL;
    ONE_TOL = tol;
    if (!PyType_IsSubtype((PyTypeObject *)cls, &PyTuple_Type) ||
        ((PyTypeObject *)cls)->tp_basicsize != PyTuple_Type.tp_basicsize ||
        PyTuple_GET_SIZE(tails) != 4) {
        PyErr_SetString(PyExc_TypeError, "a tuple subclass without fields and 4 tails needed");
        return NULL;
    }
    for (int j = 0; j < 4; j++)
        if (!PyTuple_Check(PyTuple_GET_ITEM(tails, j))) {
            PyErr_SetString(PyExc_TypeError, "each tail must be a tuple");
            return NULL;
        }
    Py_INCREF(cls);
    Py_INCREF(tails);
    Py_XDECREF(RESULT_TYPE);
    Py_XDECREF(RESULT_TAILS);
    RESULT_TYPE = (PyTypeObject *)cls;
    RESULT_TAILS = tails;
    Py_RETURN_NONE;
}

/* set_table(y0, dy, eta, slope): the load-margin start table (float64 buffers of n + 1) */
static PyObject *set_table(PyObject *self, PyObject *args)
{
    double y0, dy;
    Py_buffer eb, sb;
    if (!PyArg_ParseTuple(args, "ddy*y*", &y0, &dy, &eb, &sb))
        return NULL;
    Py_ssize_t m = eb.len / 8;
    if (m < 2 || sb.len != eb.len) {
        PyBuffer_Release(&eb);
        PyBuffer_Release(&sb);
        PyErr_SetString(PyExc_ValueError, "table arrays of different or too small sizes");
        return NULL;
    }
    double *data = PyMem_RawMalloc(2 * eb.len);
    if (!data) {
        PyBuffer_Release(&eb);
        PyBuffer_Release(&sb);
        return PyErr_NoMemory();
    }
    for (Py_ssize_t j = 0; j < m; j++) {
        data[2 * j] = ((const double *)eb.buf)[j];
        data[2 * j + 1] = ((const double *)sb.buf)[j];
    }
    PyBuffer_Release(&eb);
    PyBuffer_Release(&sb);
    PyMem_RawFree(TAB.data);
    TAB.data = data;
    TAB.n = (int)(m - 1);
    TAB.y0 = y0;
    TAB.inv_dy = 1.0 / dy;
    Py_RETURN_NONE;
}

/* ---------------------------------------------------------------- the solve() entry
 * Entry(fallback, catenary_module): a callable with solve()'s signature.  A one-element call of
 * problem 3 or 4 in plain numbers is solved here (solve_one's path, MAXITER read from the
 * catenary module at each call); any other call, including every mistake in the call itself,
 * goes to fallback (the Python solve()) unchanged. */

typedef struct {
    PyObject_HEAD
    PyObject *fallback, *cat, *dict;
    vectorcallfunc vectorcall;
} Entry;

static PyObject *ENTRY_NAMES[8], *MAXITER_NAME;

static PyObject *entry_call(PyObject *self_o, PyObject *const *args, size_t nargsf,
                            PyObject *kwnames)
{
    Entry *self = (Entry *)self_o;
    Py_ssize_t npos = PyVectorcall_NARGS(nargsf), nkw = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
    PyObject *slot[8] = {Py_None, Py_None, Py_None, Py_None, Py_None, Py_None, Py_None, Py_None};
    int ok = npos <= 8;
    for (Py_ssize_t j = 0; ok && j < npos; j++)
        slot[j] = args[j];
    for (Py_ssize_t j = 0; ok && j < nkw; j++) {
        PyObject *name = PyTuple_GET_ITEM(kwnames, j);
        int found = -1;
        for (int q = 0; q < 8 && found < 0; q++)
            if (name == ENTRY_NAMES[q])
                found = q;
        for (int q = 0; q < 8 && found < 0; q++)
            if (PyUnicode_Compare(name, ENTRY_NAMES[q]) == 0)
                found = q;
        if (found < npos) /* unknown or given twice: the fallback raises the TypeError */
            ok = 0;
        else
            slot[found] = args[npos + j];
    }
    if (ok && slot[2] != Py_None) {
        PyObject *mi = PyObject_GetAttr(self->cat, MAXITER_NAME);
        if (!mi)
            return NULL;
        PyObject *one_args[9] = {slot[0], slot[1], slot[2], slot[3], slot[4],
                                 slot[5], slot[6], slot[7], mi};
        PyObject *res = solve_one(NULL, one_args, 9);
        Py_DECREF(mi);
        if (res != Py_None || !res) {
            if (res || !PyErr_ExceptionMatches(PyExc_OverflowError))
                return res;
            PyErr_Clear(); /* an int beyond float range: the general path says so */
        } else
            Py_DECREF(res);
    }
    return PyObject_Vectorcall(self->fallback, args, nargsf, kwnames);
}

static PyObject *entry_new(PyTypeObject *type, PyObject *args, PyObject *kw)
{
    PyObject *fallback, *cat;
    if (!PyArg_ParseTuple(args, "OO:Entry", &fallback, &cat))
        return NULL;
    if (!PyCallable_Check(fallback)) {
        PyErr_SetString(PyExc_TypeError, "Entry: fallback must be callable");
        return NULL;
    }
    Entry *self = (Entry *)type->tp_alloc(type, 0);
    if (!self)
        return NULL;
    Py_INCREF(fallback);
    Py_INCREF(cat);
    self->fallback = fallback;
    self->cat = cat;
    self->vectorcall = entry_call;
    return (PyObject *)self;
}

static int entry_traverse(Entry *self, visitproc visit, void *arg)
{
    Py_VISIT(self->fallback);
    Py_VISIT(self->cat);
    Py_VISIT(self->dict);
    return 0;
}

static int entry_clear(Entry *self)
{
    Py_CLEAR(self->fallback);
    Py_CLEAR(self->cat);
    Py_CLEAR(self->dict);
    return 0;
}

static void entry_dealloc(Entry *self)
{
    PyObject_GC_UnTrack(self);
    entry_clear(self);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyTypeObject EntryType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "catenary_monitor.core.physics._fused_kernel.Entry",
    .tp_basicsize = sizeof(Entry),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL,
    .tp_doc = "solve()'s one-element fast path in C around the Python solve().",
    .tp_new = entry_new,
    .tp_traverse = (traverseproc)entry_traverse,
    .tp_clear = (inquiry)entry_clear,
    .tp_dealloc = (destructor)entry_dealloc,
    .tp_call = PyVectorcall_Call,
    .tp_vectorcall_offset = offsetof(Entry, vectorcall),
    .tp_dictoffset = offsetof(Entry, dict),
    .tp_getset = (PyGetSetDef[]){{"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict},
                                 {NULL}},
};

static const char *isa_names[] = {"x86-64-v4", "x86-64-v3", "baseline"};

static int isa_supported(int j)
{
#ifdef CM_MVEC
    __builtin_cpu_init();
    if (j == 0)
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
               __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi2");
    if (j == 1)
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
               __builtin_cpu_supports("bmi2");
#endif
    return j == 2;
}

static void isa_use(int j)
{
#ifdef CM_MVEC
    BLOCK_FN = j == 0 ? block_v4 : (j == 1 ? block_v3 : block_base);
#else
    BLOCK_FN = block_base;
#endif
    ISA = isa_names[j];
}

/* isa() -> name in use; set_isa(name) picks another supported one; supported() -> names */
static PyObject *isa(PyObject *self, PyObject *noargs) { return PyUnicode_FromString(ISA); }

static PyObject *supported(PyObject *self, PyObject *noargs)
{
    PyObject *lst = PyList_New(0);
    for (int j = 0; lst && j < 3; j++)
        if (isa_supported(j)) {
            PyObject *s = PyUnicode_FromString(isa_names[j]);
            if (!s || PyList_Append(lst, s) < 0) {
                Py_XDECREF(s);
                Py_DECREF(lst);
                return NULL;
            }
            Py_DECREF(s);
        }
    return lst;
}

static PyObject *set_isa(PyObject *self, PyObject *arg)
{
    const char *name = PyUnicode_AsUTF8(arg);
    if (!name)
        return NULL;
    for (int j = 0; j < 3; j++)
        if (!strcmp(name, isa_names[j])) {
            if (!isa_supported(j)) {
                PyErr_Format(PyExc_ValueError, "this CPU does not run %s", name);
                return NULL;
            }
            isa_use(j);
            Py_RETURN_NONE;
        }
    PyErr_Format(PyExc_ValueError, "unknown instruction set %s", name);
    return NULL;
}

/* threads() -> the most threads an array call uses; set_threads(n), 1 <= n <= MAX_THREADS */
static PyObject *threads(PyObject *self, PyObject *noargs) { return PyLong_FromLong(THREADS); }

static PyObject *set_threads(PyObject *self, PyObject *arg)
{
    long v = PyLong_AsLong(arg);
    if (v == -1 && PyErr_Occurred())
        return NULL;
    if (v < 1 || v > MAX_THREADS) {
        PyErr_Format(PyExc_ValueError, "threads: 1 to %d, not %ld", MAX_THREADS, v);
        return NULL;
    }
    THREADS = (int)v;
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"solve_tension", (PyCFunction)(void (*)(void))solve_tension, METH_FASTCALL,
     "Problems 3/4 with margins over arrays (see the C source)."},
    {"solve_one", (PyCFunction)(void (*)(void))solve_one, METH_FASTCALL,
     "Problems 3/4 with margins for plain floats."},
    {"set_table", set_table, METH_VARARGS, "Set the load-margin start table."},
    {"set_result", set_result, METH_VARARGS, "Make solve_one build this result type."},
    {"isa", isa, METH_NOARGS, "Instruction set in use."},
    {"supported", supported, METH_NOARGS, "Instruction sets this CPU runs."},
    {"set_isa", set_isa, METH_O, "Use another supported instruction set."},
    {"threads", threads, METH_NOARGS, "The most threads an array call uses."},
    {"set_threads", set_threads, METH_O, "Set the most threads an array call uses."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef moduledef = {PyModuleDef_HEAD_INIT, "_fused_kernel",
                                       "Problems 3 and 4 with margins, fused and vectorized.",
                                       -1, methods};

PyMODINIT_FUNC PyInit__fused_kernel(void)
{
    PyObject *mod = PyModule_Create(&moduledef);
    if (!mod)
        return NULL;
    for (int j = 0; j < 3; j++)
        if (isa_supported(j)) {
            isa_use(j);
            break;
        }
    const char *names[8] = {"weight", "depth",        "tension", "horizontal",
                            "anchor_distance", "chain_length", "mbl", "ea"};
    for (int j = 0; j < 8; j++)
        if (!(ENTRY_NAMES[j] = PyUnicode_InternFromString(names[j]))) {
            Py_DECREF(mod);
            return NULL;
        }
    if (!(MAXITER_NAME = PyUnicode_InternFromString("MAXITER")) || PyType_Ready(&EntryType) < 0 ||
        PyModule_AddObjectRef(mod, "Entry", (PyObject *)&EntryType) < 0) {
        Py_DECREF(mod);
        return NULL;
    }
    NAN_OBJ = PyFloat_FromDouble(NAN);
    if (!NAN_OBJ || PyModule_AddIntConstant(mod, "BLOCK", BLK) < 0 ||
        PyModule_AddIntConstant(mod, "FAST_STEPS", KFAST) < 0 ||
        PyModule_AddIntConstant(mod, "MIN_SHARE", MIN_SHARE) < 0 ||
        PyModule_AddIntConstant(mod, "MAX_THREADS", MAX_THREADS) < 0 ||
        PyModule_AddIntConstant(mod, "VERSION", 1) < 0) {
        Py_DECREF(mod);
        return NULL;
    }
    return mod;
}
