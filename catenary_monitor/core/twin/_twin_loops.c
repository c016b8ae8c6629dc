/* Three loops of the vectorized twin's schedule (catenary_monitor/core/twin/engine.py) in C.
 *
 * Optional, like the solve kernel: where it is not built, twin.py runs its numpy passes,
 * which give the same arrays (test/test_batch_steps.py compares them).
 *
 *   merge3(dd, tt, kk, times_out, kinds_out, kind_d, kind_t, kind_k) -> bool
 *       twin._merge: the sorted depth, tension and tick times (int64) merged into one
 *       schedule, ties taken depth, tension, tick; False (nothing written) when an input is
 *       not sorted, for the caller's numpy path.
 *   pick(idx, column, before, out)
 *       twin._pick for a float64 column: out[i] = column[idx[i]], or `before` where
 *       idx[i] == -1 (every element `before` when the column is empty).
 *   newest(kinds, kind_d, kind_t, kind_k, known, t_idx, d_idx, dk_idx, k_idx, solved, s_idx)
 *       twin._line_steps: per step (kinds int8: the depth, tension or tick code), the index of
 *       the newest tension, depth, non-tension and tick step within its kind (int64, -1:
 *       none yet); whether the line is solved there (a tension; a depth once a tension is
 *       known, `known` or one in the window) and the index of the newest solved step.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

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

static int sorted64(const int64_t *a, Py_ssize_t n) {
    for (Py_ssize_t i = 1; i < n; i++)
        if (a[i] < a[i - 1]) return 0;
    return 1;
}

static PyObject *py_merge3(PyObject *self, PyObject *args) {
    PyObject *o[5];
    int kind[3];
    if (!PyArg_ParseTuple(args, "OOOOOiii", &o[0], &o[1], &o[2], &o[3], &o[4], &kind[0],
                          &kind[1], &kind[2]))
        return NULL;
    Py_buffer b[5];
    const Py_ssize_t size[5] = {8, 8, 8, 8, 1};
    const char *names[5] = {"dd", "tt", "kk", "times_out", "kinds_out"};
    int got = 0;
    PyObject *result = NULL;
    for (; got < 5; got++)
        if (get(o[got], &b[got], got >= 3, size[got], names[got]) < 0) goto done;
    const int64_t *d = b[0].buf, *t = b[1].buf, *k = b[2].buf;
    const Py_ssize_t nd = b[0].len / 8, nt = b[1].len / 8, nk = b[2].len / 8;
    const Py_ssize_t n = nd + nt + nk;
    if (b[3].len != 8 * n || b[4].len != n) {
        PyErr_SetString(PyExc_ValueError, "merge3: outputs of the wrong size");
        goto done;
    }
    if (!sorted64(d, nd) || !sorted64(t, nt) || !sorted64(k, nk)) {
        Py_INCREF(Py_False);
        result = Py_False;
        goto done;
    }
    int64_t *times = b[3].buf;
    int8_t *kinds = b[4].buf;
    Py_ssize_t i = 0, j = 0, m = 0;
    for (Py_ssize_t at = 0; at < n; at++) {
        /* depth if it is not later than the others; tension if not later than the tick */
        if (i < nd && (j >= nt || d[i] <= t[j]) && (m >= nk || d[i] <= k[m])) {
            times[at] = d[i++];
            kinds[at] = (int8_t)kind[0];
        } else if (j < nt && (m >= nk || t[j] <= k[m])) {
            times[at] = t[j++];
            kinds[at] = (int8_t)kind[1];
        } else {
            times[at] = k[m++];
            kinds[at] = (int8_t)kind[2];
        }
    }
    Py_INCREF(Py_True);
    result = Py_True;
done:
    for (int g = 0; g < got; g++) PyBuffer_Release(&b[g]);
    return result;
}

static PyObject *py_pick(PyObject *self, PyObject *args) {
    PyObject *o_idx, *o_col, *o_out;
    double before;
    if (!PyArg_ParseTuple(args, "OOdO", &o_idx, &o_col, &before, &o_out)) return NULL;
    Py_buffer bi, bc, bo;
    PyObject *result = NULL;
    if (get(o_idx, &bi, 0, 8, "idx") < 0) return NULL;
    if (get(o_col, &bc, 0, 8, "column") < 0) { PyBuffer_Release(&bi); return NULL; }
    if (get(o_out, &bo, 1, 8, "out") < 0) {
        PyBuffer_Release(&bi);
        PyBuffer_Release(&bc);
        return NULL;
    }
    const int64_t *idx = bi.buf;
    const double *col = bc.buf;
    double *out = bo.buf;
    const Py_ssize_t n = bi.len / 8, nc = bc.len / 8;
    if (bo.len != bi.len) {
        PyErr_SetString(PyExc_ValueError, "pick: out and idx differ in length");
        goto done;
    }
    if (nc == 0) {
        for (Py_ssize_t i = 0; i < n; i++) out[i] = before;
    } else {
        for (Py_ssize_t i = 0; i < n; i++) {
            const int64_t j = idx[i];
            if (j < -1 || j >= nc) {
                PyErr_SetString(PyExc_IndexError, "pick: index out of range");
                goto done;
            }
            out[i] = j < 0 ? before : col[j];
        }
    }
    Py_INCREF(Py_None);
    result = Py_None;
done:
    PyBuffer_Release(&bi);
    PyBuffer_Release(&bc);
    PyBuffer_Release(&bo);
    return result;
}

static PyObject *py_newest(PyObject *self, PyObject *args) {
    PyObject *o[7];
    int kd, kt, kk, known;
    if (!PyArg_ParseTuple(args, "OiiipOOOOOO", &o[0], &kd, &kt, &kk, &known, &o[1], &o[2],
                          &o[3], &o[4], &o[5], &o[6]))
        return NULL;
    Py_buffer b[7];
    const Py_ssize_t size[7] = {1, 8, 8, 8, 8, 1, 8};
    const char *names[7] = {"kinds", "t_idx", "d_idx", "dk_idx", "k_idx", "solved", "s_idx"};
    int got = 0;
    PyObject *result = NULL;
    for (; got < 7; got++)
        if (get(o[got], &b[got], got > 0, size[got], names[got]) < 0)
            goto done;
    const int8_t *kinds = b[0].buf;
    const Py_ssize_t n = b[0].len;
    for (int g = 1; g < 7; g++)
        if (b[g].len != n * size[g]) {
            PyErr_SetString(PyExc_ValueError, "newest: outputs of the wrong size");
            goto done;
        }
    int64_t *ti = b[1].buf, *di = b[2].buf, *dki = b[3].buf, *ki = b[4].buf, *si = b[6].buf;
    uint8_t *solved = b[5].buf;
    int64_t nt = -1, nd = -1, ndk = -1, nk = -1, ns = -1;
    for (Py_ssize_t i = 0; i < n; i++) {
        const int k = kinds[i];
        int s = 0;
        if (k == kt) {
            nt++;
            known = 1;
            s = 1;
        } else {
            ndk++;
            if (k == kd) {
                nd++;
                s = known;
            } else if (k == kk) {
                nk++;
            } else {
                PyErr_Format(PyExc_ValueError, "newest: unknown step kind %d", k);
                goto done;
            }
        }
        ns += s;
        ti[i] = nt, di[i] = nd, dki[i] = ndk, ki[i] = nk, si[i] = ns;
        solved[i] = (uint8_t)s;
    }
    Py_INCREF(Py_None);
    result = Py_None;
done:
    for (int g = 0; g < got; g++) PyBuffer_Release(&b[g]);
    return result;
}

static PyMethodDef methods[] = {
    {"merge3", py_merge3, METH_VARARGS, "Merge sorted depth, tension and tick times."},
    {"pick", py_pick, METH_VARARGS, "column[idx], before where idx == -1 (float64)."},
    {"newest", py_newest, METH_VARARGS, "Per step: the newest index of each kind."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_twin_loops", NULL, -1, methods};

PyMODINIT_FUNC PyInit__twin_loops(void) { return PyModule_Create(&module); }
