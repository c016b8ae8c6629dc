/* The fatigue count's column loop (catenary_monitor/core/rules/fatigue.py) in C.
 *
 * Optional, like the solve kernel: where it is not built, fatigue.series runs fatigue.step in
 * a Python loop, which gives the same bits (test/test_fatigue.py compares them).
 *
 *   fatigue(t, tension, scale, m, inv_a, limit, residue, halves, n_res, marks, n_marks, closed,
 *           fixed, residue_max, mark_every, rate_window, rate_min_span, damage, rate, life)
 *       -> (closed, fixed, n_res, n_marks)
 *       fatigue.series: fatigue.step per sample (the streamed rainflow residue, Miner's damage,
 *       the rate marks), the same operations in the same order; residue and halves (float64,
 *       room for residue_max + 2) and marks ((k, 2) float64) are updated in place.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

static int get(PyObject *obj, Py_buffer *b, int writable, Py_ssize_t itemsize,
               const char *name) {
    if (PyObject_GetBuffer(obj, b, (writable ? PyBUF_WRITABLE : 0) | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (b->len % itemsize) {
        PyErr_Format(PyExc_ValueError, "%s: %zd B is not a whole number of items", name,
                     b->len);
        PyBuffer_Release(b);
        return -1;
    }
    return 0;
}

/* fatigue.cycle_damage: (|range| * scale)^m * inv_a */
static double cycle_damage(double range, double scale, double m, double inv_a) {
    return pow(fabs(range) * scale, m) * inv_a;
}

static PyObject *py_fatigue(PyObject *self, PyObject *args) {
    PyObject *o[8];
    double scale, m, inv_a, limit, closed, fixed, mark_every, window, min_span;
    Py_ssize_t n_res, n_marks, res_max;
    if (!PyArg_ParseTuple(args, "OOddddOOnOnddndddOOO", &o[0], &o[1], &scale, &m, &inv_a, &limit,
                          &o[2], &o[3], &n_res, &o[4], &n_marks, &closed, &fixed, &res_max,
                          &mark_every, &window, &min_span, &o[5], &o[6], &o[7]))
        return NULL;
    Py_buffer b[8];
    const int writable[8] = {0, 0, 1, 1, 1, 1, 1, 1};
    const char *names[8] = {"t", "tension", "residue", "halves", "marks",
                            "damage", "rate", "life"};
    int got = 0;
    PyObject *result = NULL;
    for (; got < 8; got++)
        if (get(o[got], &b[got], writable[got], 8, names[got]) < 0) goto done;
    const double *t = b[0].buf, *x = b[1].buf;
    double *r = b[2].buf, *h = b[3].buf, *mk = b[4].buf;
    double *dmg = b[5].buf, *rate = b[6].buf, *life = b[7].buf;
    const Py_ssize_t n = b[0].len / 8, cap_marks = b[4].len / 16;
    if (b[1].len != 8 * n || b[5].len != 8 * n || b[6].len != 8 * n || b[7].len != 8 * n ||
        b[2].len < 8 * (res_max + 2) || b[3].len < 8 * (res_max + 2) || n_res > res_max ||
        n_marks > cap_marks) {
        PyErr_SetString(PyExc_ValueError, "fatigue: arrays of the wrong size");
        goto done;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        const double v = x[i], now = t[i];
        if (isfinite(v) && v >= 0.0 && v <= limit && !(n_res && v == r[n_res - 1])) {
            if (n_res < 2 || (v - r[n_res - 1]) * (r[n_res - 1] - r[n_res - 2]) <= 0.0) {
                if (n_res) fixed += h[n_res - 1];
                r[n_res] = v;
                h[n_res] = n_res ? 0.5 * cycle_damage(v - r[n_res - 1], scale, m, inv_a) : 0.0;
                n_res++;
            } else {
                r[n_res - 1] = v;
                h[n_res - 1] = 0.5 * cycle_damage(v - r[n_res - 2], scale, m, inv_a);
            }
            while (n_res >= 4) {
                const double a = r[n_res - 4], bb = r[n_res - 3], c = r[n_res - 2],
                             d = r[n_res - 1];
                const double inner = fabs(c - bb);
                if (!(inner <= fabs(bb - a) && inner <= fabs(d - c))) break;
                closed += cycle_damage(inner, scale, m, inv_a);
                fixed -= h[n_res - 3] + h[n_res - 2];
                r[n_res - 3] = d;
                n_res -= 2;
                h[n_res - 1] = 0.5 * cycle_damage(d - a, scale, m, inv_a);
            }
            if (n_res > res_max) {
                closed += h[1];
                fixed -= h[1];
                memmove(r, r + 1, (size_t)(n_res - 1) * sizeof(double));
                memmove(h, h + 1, (size_t)(n_res - 1) * sizeof(double));
                n_res--;
                h[0] = 0.0;
            }
        }
        const double damage = closed + fixed + (n_res ? h[n_res - 1] : 0.0);
        if (!n_marks || now >= mk[2 * (n_marks - 1)] + mark_every) {
            if (n_marks == cap_marks) {
                PyErr_SetString(PyExc_ValueError, "fatigue: too many rate marks");
                goto done;
            }
            mk[2 * n_marks] = now;
            mk[2 * n_marks + 1] = damage;
            n_marks++;
        }
        Py_ssize_t k = 0;
        while (k < n_marks - 1 && mk[2 * k] < now - window) k++;
        if (k) {
            memmove(mk, mk + 2 * k, (size_t)(n_marks - k) * 2 * sizeof(double));
            n_marks -= k;
        }
        const double span = now - mk[0];
        const double per_s = span >= min_span ? (damage - mk[1]) / span : NAN;
        dmg[i] = damage;
        rate[i] = per_s;
        if (damage >= 1.0)
            life[i] = 0.0;
        else if (per_s != per_s)
            life[i] = NAN;
        else
            life[i] = per_s <= 0.0 ? INFINITY : (1.0 - damage) / per_s;
    }
    result = Py_BuildValue("(ddnn)", closed, fixed, n_res, n_marks);
done:
    for (int j = 0; j < got; j++) PyBuffer_Release(&b[j]);
    return result;
}

static PyMethodDef methods[] = {
    {"fatigue", py_fatigue, METH_VARARGS, "Streamed rainflow and Miner's damage per sample."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_fatigue_loop", NULL, -1, methods};

PyMODINIT_FUNC PyInit__fatigue_loop(void) { return PyModule_Create(&module); }
