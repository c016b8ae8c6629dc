/* The MCAP reader's per-record loops in C (catenary_monitor/io/mcap_scan.py).
 *
 * Optional, like the solve kernel: where it is not built, the reader runs its numpy passes,
 * which give the same offsets, reports and columns (test/test_mcap_scan.py runs the reader's
 * damage tests both ways).  Four functions, each one pass over a batch's records:
 *
 *   locate(buf, file, table, starts, sizes, g_out, bad_out, gaps_out) -> (n_g, n_gaps)
 *       the Message Index check of Scanner._locate_messages: every entry must point inside
 *       its chunk at a Message record of its channel, records must not overlap; a chunk with a
 *       failing entry is "bad" (walked instead).  Writes the covered record starts in buffer
 *       order (g_out), the bad chunks (bad_out, 0/1) and the byte ranges that no covered
 *       record spans (gaps_out, pairs a, b), as the numpy path's sort, overlap and lexsort do.
 *   gather(buf, positions, width, out)
 *       the `width` bytes at each position, back to back (out: n * width bytes).
 *   float64_columns(buf, offsets, lengths, channels, topic_lut, ntopics, t_out, v_out,
 *                   counts_out) -> (n_good, bad)
 *       _extract_float64 and _split_topics: the log times and values of the CDR Float64
 *       records grouped by topic index (file order within each), their count per topic and
 *       the number of records that are not a 12-byte CDR Float64.
 *   walk(buf, start, end, out) -> (n, stop, status)
 *       Scanner._walk: the records of buf[start:end] one after the other, the starts of the
 *       Message records (22 B of head at least) into out (int64) until it is full; it stops
 *       where a Schema or Channel record starts (status 1: Python registers it and walks on),
 *       at a record that is not one (opcode 0, an unknown opcode below 0x80, a Message record
 *       too short for its head) or that runs past end (status 2), at end (status 0), or when
 *       out is full (status 3).
 *
 * Buffers come through the buffer protocol (numpy arrays, bytes, mmap); the caller (Python)
 * allocates the outputs and checks dtypes and sizes.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define OP_MESSAGE 0x05
#define MESSAGE_MIN (9 + 22)
#define FLOAT64_RECORD (9 + 22 + 12)

static uint64_t rd_u64(const uint8_t *p) { uint64_t v; memcpy(&v, p, 8); return v; }
static uint16_t rd_u16(const uint8_t *p) { uint16_t v; memcpy(&v, p, 2); return v; }

typedef struct {
    Py_buffer b[9];
    int n;
} Views;

static void release(Views *v) {
    for (int i = 0; i < v->n; i++) PyBuffer_Release(&v->b[i]);
    v->n = 0;
}

/* Get a C-contiguous view of obj of at least `min_len` bytes (writable if asked). */
static Py_buffer *view(Views *v, PyObject *obj, int writable, Py_ssize_t min_len,
                       const char *name) {
    Py_buffer *b = &v->b[v->n];
    if (PyObject_GetBuffer(obj, b, (writable ? PyBUF_WRITABLE : 0) | PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    v->n++;
    if (b->len < min_len) {
        PyErr_Format(PyExc_ValueError, "%s: %zd B, need %zd", name, b->len, min_len);
        return NULL;
    }
    return b;
}

static PyObject *py_locate(PyObject *self, PyObject *args) {
    PyObject *o_buf, *o_file, *o_table, *o_starts, *o_sizes, *o_g, *o_bad, *o_gaps;
    if (!PyArg_ParseTuple(args, "OOOOOOOO", &o_buf, &o_file, &o_table, &o_starts, &o_sizes,
                          &o_g, &o_bad, &o_gaps))
        return NULL;
    Views v = {.n = 0};
    PyObject *result = NULL;
    uint8_t *bits = NULL;
    Py_buffer *buf = view(&v, o_buf, 0, 0, "buf");
    Py_buffer *file = buf ? view(&v, o_file, 0, 0, "file") : NULL;
    Py_buffer *table = file ? view(&v, o_table, 0, 0, "table") : NULL;
    Py_buffer *starts = table ? view(&v, o_starts, 0, 0, "starts") : NULL;
    if (!starts) goto done;
    Py_ssize_t k = starts->len / 8, m = table->len / 32;
    Py_buffer *sizes = view(&v, o_sizes, 0, 8 * k, "sizes");
    Py_buffer *bad = sizes ? view(&v, o_bad, 1, k, "bad") : NULL;
    if (!bad) goto done;
    const int64_t *tab = (const int64_t *)table->buf;
    const int64_t *st = (const int64_t *)starts->buf, *sz = (const int64_t *)sizes->buf;
    int64_t total = 0, max_size = 0;
    for (Py_ssize_t r = 0; r < m; r++) {
        if (tab[4 * r + 3] < 0 || tab[4 * r] < 0 || tab[4 * r] >= k ||
            (r && tab[4 * r] < tab[4 * (r - 1)])) {
            PyErr_SetString(PyExc_ValueError, "table: bad row (piece order, count)");
            goto done;
        }
        total += tab[4 * r + 3];
    }
    for (Py_ssize_t p = 0; p < k; p++) {
        if (sz[p] < 0 || st[p] < 0 || st[p] + sz[p] > buf->len) {
            PyErr_SetString(PyExc_ValueError, "starts/sizes outside buf");
            goto done;
        }
        if (sz[p] > max_size) max_size = sz[p];
    }
    Py_buffer *g_b = view(&v, o_g, 1, 8 * total, "g_out");
    Py_buffer *gaps_b = g_b ? view(&v, o_gaps, 1, 16 * (total + k), "gaps_out") : NULL;
    if (!gaps_b) goto done;
    bits = calloc((size_t)(max_size / 64 + 1), 8);
    if (!bits) { PyErr_NoMemory(); goto done; }

    const uint8_t *a = (const uint8_t *)buf->buf, *f = (const uint8_t *)file->buf;
    const Py_ssize_t alen = buf->len, flen = file->len;
    int64_t *g = (int64_t *)g_b->buf, *gaps = (int64_t *)gaps_b->buf;
    uint8_t *badp = (uint8_t *)bad->buf;
    uint64_t *words = (uint64_t *)bits;
    int64_t ng = 0, ngap = 0;
    Py_ssize_t r = 0;
    int outside = 0;  /* an index entry outside the file: raised once the GIL is back */
    Py_BEGIN_ALLOW_THREADS;  /* plain memory from here: the read-ahead thread runs beside */
    for (Py_ssize_t p = 0; p < k && !outside; p++) {
        const int64_t start = st[p], size = sz[p], end = start + size;
        Py_ssize_t r0 = r;
        int64_t entries = 0;
        while (r < m && tab[4 * r] == p) entries += tab[4 * r++ + 3];
        int is_bad = 0;
        int64_t g0 = ng;
        if (entries) {
            const int64_t nwords = size / 64 + 1;
            memset(words, 0, (size_t)nwords * 8);
            if (alen < MESSAGE_MIN) is_bad = 1;
            for (Py_ssize_t rr = r0; rr < r && !is_bad; rr++) {
                const int64_t cid = tab[4 * rr + 1], at = tab[4 * rr + 2], count = tab[4 * rr + 3];
                if (at < 0 || at + 16 * count > flen) { outside = 1; break; }
                for (int64_t w = 0; w < count; w++) {
                    const uint64_t off = rd_u64(f + at + 16 * w + 8);
                    if (off >= (uint64_t)size || (int64_t)off + MESSAGE_MIN > size) { is_bad = 1; break; }
                    const uint8_t *h = a + start + (int64_t)off;
                    const uint64_t length = rd_u64(h + 1);
                    if (h[0] != OP_MESSAGE || rd_u16(h + 9) != (uint64_t)cid || length < 22 ||
                        length > (uint64_t)size ||
                        start + (int64_t)off + 9 + (int64_t)length > end) { is_bad = 1; break; }
                    uint64_t *word = words + (off >> 6), bit = (uint64_t)1 << (off & 63);
                    if (*word & bit) { is_bad = 1; break; }  /* two entries, one record */
                    *word |= bit;
                }
            }
            if (outside) break;
            if (!is_bad) {  /* the records in buffer order; no overlap */
                int64_t prev_e = start;
                for (int64_t wi = 0; wi < nwords && !is_bad; wi++) {
                    uint64_t word = words[wi];
                    while (word) {
                        const int64_t at = start + wi * 64 + __builtin_ctzll(word);
                        word &= word - 1;
                        if (ng > g0 && prev_e > at) { is_bad = 1; break; }
                        g[ng++] = at;
                        prev_e = at + 9 + (int64_t)rd_u64(a + at + 1);
                    }
                }
            }
        }
        badp[p] = (uint8_t)is_bad;
        if (is_bad) ng = g0;
        /* the ranges no covered record spans */
        int64_t cursor = start;
        for (int64_t i = g0; i < ng; i++) {
            if (cursor < g[i]) { gaps[2 * ngap] = cursor; gaps[2 * ngap + 1] = g[i]; ngap++; }
            cursor = g[i] + 9 + (int64_t)rd_u64(a + g[i] + 1);
        }
        if (cursor < end) { gaps[2 * ngap] = cursor; gaps[2 * ngap + 1] = end; ngap++; }
    }
    Py_END_ALLOW_THREADS;
    if (outside) {
        PyErr_SetString(PyExc_ValueError, "table: index entries outside file");
        goto done;
    }
    result = Py_BuildValue("nn", (Py_ssize_t)ng, (Py_ssize_t)ngap);
done:
    free(bits);
    release(&v);
    return result;
}

static PyObject *py_gather(PyObject *self, PyObject *args) {
    PyObject *o_buf, *o_pos, *o_out;
    Py_ssize_t width;
    if (!PyArg_ParseTuple(args, "OOnO", &o_buf, &o_pos, &width, &o_out)) return NULL;
    Views v = {.n = 0};
    PyObject *result = NULL;
    Py_buffer *buf = view(&v, o_buf, 0, 0, "buf");
    Py_buffer *pos = buf ? view(&v, o_pos, 0, 0, "positions") : NULL;
    if (!pos) goto done;
    Py_ssize_t n = pos->len / 8;
    Py_buffer *out = view(&v, o_out, 1, n * width, "out");
    if (!out) goto done;
    const uint8_t *a = (const uint8_t *)buf->buf;
    const int64_t *ps = (const int64_t *)pos->buf;
    uint8_t *o = (uint8_t *)out->buf;
    for (Py_ssize_t i = 0; i < n; i++)
        if (ps[i] < 0 || ps[i] + width > buf->len) {
            PyErr_SetString(PyExc_IndexError, "gather: position outside buf");
            goto done;
        }
    Py_BEGIN_ALLOW_THREADS;
    if (width == 2)
        for (Py_ssize_t i = 0; i < n; i++) memcpy(o + 2 * i, a + ps[i], 2);
    else if (width == 8)
        for (Py_ssize_t i = 0; i < n; i++) memcpy(o + 8 * i, a + ps[i], 8);
    else
        for (Py_ssize_t i = 0; i < n; i++) memcpy(o + width * i, a + ps[i], (size_t)width);
    Py_END_ALLOW_THREADS;
    Py_INCREF(Py_None);
    result = Py_None;
done:
    release(&v);
    return result;
}

static PyObject *py_float64_columns(PyObject *self, PyObject *args) {
    PyObject *o_buf, *o_off, *o_len, *o_ch, *o_lut, *o_t, *o_v, *o_counts;
    Py_ssize_t ntopics;
    if (!PyArg_ParseTuple(args, "OOOOOnOOO", &o_buf, &o_off, &o_len, &o_ch, &o_lut, &ntopics,
                          &o_t, &o_v, &o_counts))
        return NULL;
    Views v = {.n = 0};
    PyObject *result = NULL;
    int32_t *topic = NULL;
    int64_t *at = NULL;
    Py_buffer *buf = view(&v, o_buf, 0, 0, "buf");
    Py_buffer *off = buf ? view(&v, o_off, 0, 0, "offsets") : NULL;
    if (!off) goto done;
    const Py_ssize_t n = off->len / 8;
    Py_buffer *len = view(&v, o_len, 0, 8 * n, "lengths");
    Py_buffer *ch = len ? view(&v, o_ch, 0, 2 * n, "channels") : NULL;
    Py_buffer *lut = ch ? view(&v, o_lut, 0, 8 * 65536, "topic_lut") : NULL;
    Py_buffer *t_b = lut ? view(&v, o_t, 1, 8 * n, "t_out") : NULL;
    Py_buffer *v_b = t_b ? view(&v, o_v, 1, 8 * n, "v_out") : NULL;
    Py_buffer *c_b = v_b ? view(&v, o_counts, 1, 8 * ntopics, "counts_out") : NULL;
    if (!c_b) goto done;
    topic = malloc((size_t)(n ? n : 1) * sizeof(int32_t));
    if (!topic) { PyErr_NoMemory(); goto done; }
    const uint8_t *a = (const uint8_t *)buf->buf;
    const int64_t *os = (const int64_t *)off->buf, *ls = (const int64_t *)len->buf;
    const uint16_t *cs = (const uint16_t *)ch->buf;
    const int64_t *lt = (const int64_t *)lut->buf;
    int64_t *counts = (int64_t *)c_b->buf, *t_out = (int64_t *)t_b->buf;
    double *v_out = (double *)v_b->buf;
    memset(counts, 0, (size_t)ntopics * 8);
    Py_ssize_t bad = 0;
    int no_topic = 0;  /* a record of a channel without topic: raised once the GIL is back */
    Py_BEGIN_ALLOW_THREADS;
    for (Py_ssize_t i = 0; i < n; i++) {
        topic[i] = -1;
        if (ls[i] < FLOAT64_RECORD - 9 || os[i] < 0 || os[i] + FLOAT64_RECORD > buf->len) {
            bad++;
            continue;
        }
        const uint8_t *r = a + os[i];
        if (r[31] != 0 || r[32] > 1) {  /* encapsulation 00 00 (BE) or 00 01 (LE) */
            bad++;
            continue;
        }
        const int64_t tp = lt[cs[i]];
        if (tp < 0 || tp >= ntopics) { no_topic = 1; break; }
        topic[i] = (int32_t)tp;
        counts[tp]++;
    }
    Py_END_ALLOW_THREADS;
    if (no_topic) {
        PyErr_SetString(PyExc_ValueError, "a record of a channel without topic");
        goto done;
    }
    at = malloc((size_t)(ntopics > 0 ? ntopics : 1) * sizeof(int64_t));
    if (!at) { PyErr_NoMemory(); goto done; }
    int64_t sum = 0;
    Py_BEGIN_ALLOW_THREADS;
    for (Py_ssize_t j = 0; j < ntopics; j++) { at[j] = sum; sum += counts[j]; }
    for (Py_ssize_t i = 0; i < n; i++) {
        if (topic[i] < 0) continue;
        const uint8_t *r = a + os[i];
        const int64_t j = at[topic[i]]++;
        t_out[j] = (int64_t)rd_u64(r + 15);
        if (r[32] == 1) {
            memcpy(&v_out[j], r + 35, 8);
        } else {
            uint64_t u = __builtin_bswap64(rd_u64(r + 35));
            memcpy(&v_out[j], &u, 8);
        }
    }
    Py_END_ALLOW_THREADS;
    result = Py_BuildValue("nn", (Py_ssize_t)sum, bad);
done:
    free(at);
    free(topic);
    release(&v);
    return result;
}

static PyObject *py_walk(PyObject *self, PyObject *args) {
    PyObject *o_buf, *o_out;
    Py_ssize_t start, end;
    if (!PyArg_ParseTuple(args, "OnnO", &o_buf, &start, &end, &o_out)) return NULL;
    Views v = {.n = 0};
    PyObject *result = NULL;
    Py_buffer *buf = view(&v, o_buf, 0, 0, "buf");
    Py_buffer *out = buf ? view(&v, o_out, 1, 0, "out") : NULL;
    if (!out) goto done;
    if (start < 0 || end > buf->len || start > end) {
        PyErr_SetString(PyExc_ValueError, "walk: start/end outside buf");
        goto done;
    }
    const uint8_t *a = (const uint8_t *)buf->buf;
    int64_t *o = (int64_t *)out->buf;
    const Py_ssize_t cap = out->len / 8;
    Py_ssize_t n = 0, pos = start;
    int status = 0;
    while (pos + 9 <= end) {
        const uint8_t op = a[pos];
        const uint64_t length = rd_u64(a + pos + 1);
        if (length > (uint64_t)(end - pos - 9) || op == 0 || (op > 0x0F && op < 0x80)) {
            status = 2;
            break;
        }
        if (op == OP_MESSAGE) {
            if (length < 22) { status = 2; break; }
            if (n == cap) { status = 3; break; }
            o[n++] = pos;
        } else if (op == 0x03 || op == 0x04) {
            status = 1;
            break;
        }
        pos += 9 + (Py_ssize_t)length;
    }
    result = Py_BuildValue("nni", n, pos, status);
done:
    release(&v);
    return result;
}

static PyMethodDef methods[] = {
    {"walk", py_walk, METH_VARARGS, "Walk records; Message starts out (see top)."},
    {"locate", py_locate, METH_VARARGS, "Check a batch's Message Index entries (see top)."},
    {"gather", py_gather, METH_VARARGS, "The width bytes at each position, back to back."},
    {"float64_columns", py_float64_columns, METH_VARARGS,
     "CDR Float64 records as times and values grouped by topic."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_scan", NULL, -1, methods};

PyMODINIT_FUNC PyInit__scan(void) { return PyModule_Create(&module); }
