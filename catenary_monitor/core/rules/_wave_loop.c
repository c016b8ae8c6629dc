/* The wave window's column loop (catenary_monitor/core/rules/wave_window.py) in C.
 *
 * Optional, like the solve kernel: where it is not built, wave_window.series takes the
 * window's extremes from a sparse table in numpy, which gives the same numbers (maxima and
 * minima are exact; test/test_wave_window.py compares both with the scalar step).
 *
 *   extremes(times, values, m, window, peak, low)
 *       times, values: float64, the carried readings (m of them) first, then the piece's;
 *       NaN values are not valid readings. For each of the piece's readings i (peak and low
 *       hold len(times) - m items): the largest and smallest valid value among the readings
 *       j <= i with times[j] >= times[i] - window (NaN where there is none), by two monotone
 *       queues of indices: each reading enters and leaves each queue once.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdlib.h>

static int get(PyObject *obj, Py_buffer *b, int writable, const char *name) {
    if (PyObject_GetBuffer(obj, b, (writable ? PyBUF_WRITABLE : 0) | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (b->len % 8) {
        PyErr_Format(PyExc_ValueError, "%s: %zd B is not a whole number of float64", name,
                     b->len);
        PyBuffer_Release(b);
        return -1;
    }
    return 0;
}

static PyObject *py_extremes(PyObject *self, PyObject *args) {
    PyObject *o[4];
    Py_ssize_t m;
    double window;
    if (!PyArg_ParseTuple(args, "OOndOO", &o[0], &o[1], &m, &window, &o[2], &o[3])) return NULL;
    Py_buffer b[4];
    const int writable[4] = {0, 0, 1, 1};
    const char *names[4] = {"times", "values", "peak", "low"};
    int got = 0;
    PyObject *result = NULL;
    Py_ssize_t *high = NULL, *lowq = NULL;
    for (; got < 4; got++)
        if (get(o[got], &b[got], writable[got], names[got]) < 0) goto done;
    const double *t = b[0].buf, *v = b[1].buf;
    double *peak = b[2].buf, *low = b[3].buf;
    const Py_ssize_t total = b[0].len / 8, n = total - m;
    if (m < 0 || n < 0 || b[1].len != b[0].len || b[2].len != 8 * n || b[3].len != 8 * n) {
        PyErr_SetString(PyExc_ValueError, "extremes: arrays of the wrong size");
        goto done;
    }
    high = malloc((size_t)(total ? total : 1) * sizeof(Py_ssize_t));
    lowq = malloc((size_t)(total ? total : 1) * sizeof(Py_ssize_t));
    if (!high || !lowq) {
        PyErr_NoMemory();
        goto done;
    }
    Py_ssize_t h0 = 0, h1 = 0, l0 = 0, l1 = 0; /* queues [h0, h1) and [l0, l1) */
    for (Py_ssize_t j = 0; j < total; j++) {
        const double x = v[j];
        if (x == x) {
            while (h1 > h0 && v[high[h1 - 1]] <= x) h1--;
            high[h1++] = j;
            while (l1 > l0 && v[lowq[l1 - 1]] >= x) l1--;
            lowq[l1++] = j;
        }
        if (j < m) continue;
        const double start = t[j] - window;
        while (h1 > h0 && t[high[h0]] < start) h0++;
        while (l1 > l0 && t[lowq[l0]] < start) l0++;
        peak[j - m] = h1 > h0 ? v[high[h0]] : NAN;
        low[j - m] = l1 > l0 ? v[lowq[l0]] : NAN;
    }
    Py_INCREF(Py_None);
    result = Py_None;
done:
    free(high);
    free(lowq);
    for (int k = 0; k < got; k++) PyBuffer_Release(&b[k]);
    return result;
}

static PyMethodDef methods[] = {
    {"extremes", py_extremes, METH_VARARGS, "The wave window's largest and smallest readings."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_wave_loop", NULL, -1, methods};

PyMODINIT_FUNC PyInit__wave_loop(void) { return PyModule_Create(&module); }
