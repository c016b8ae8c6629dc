/* One block of problem 3/4 lanes (see _fused_kernel.c).  Included once per instruction set with
 * SFX(name) giving the suffixed name and CM_SIMD the loop pragma; every loop over lanes is
 * straight-line code with selects, so GCC vectorizes it with glibc's libmvec. */

/* catenary._uplift_residual, one lane: f and df/deta at eta = log(d) */
static void SFX(uplift_residual)(const BLOCK_T *k, int i, double eta, double *f, double *fp)
{
    double e = k->e[i], r02 = k->r02[i];
    double d = exp(eta);
    double big_x = k->xlo[i] + d;
    double em = expm1(d);
    double ed = 1.0 + em;
    double p = r02 + em / ed;
    double e1 = e + em * (1.0 + e);
    double g = 1.0 + e1;
    double ig = 1.0 / g;
    double sx = 0.5 * e1 * (1.0 + ig), cx = 0.5 * (g + ig);
    /* the factors scaled by sc, the power of 2 nearest 1/m (catenary._scale): the same bits
     * wherever nothing under- or overflows, no underflow of em p ~ m^2 for tiny m */
    int ex;
    frexp(k->m[i], &ex);
    double sc = ldexp(1.0, -ex);
    double qq = big_x / ((k->m[i] * sc) * sx);
    *f = log((em * sc) * (p * sc) * (qq * qq));
    *fp = (ed / em + 1.0 / (ed * p) - 2.0 * (cx / sx - 1.0 / big_x)) * d;
}

/* catenary.lifted_from_tension's bracketed loop, for one lane that the fast steps left moving;
 * returns 1 if it converged (k->d[i], k->iters[i] updated) */
static int SFX(uplift_safeguarded)(BLOCK_T *k, int i, int kfast, const Params *par)
{
    double eta = log(k->d[i]);
    if (!isfinite(eta))
        eta = log(k->d0[i]);
    double lo = -INFINITY, hi = log(k->d_max[i]);
    int conv = 0;
    for (int it = kfast + 1; it <= par->maxiter; it++) {
        double f, fp;
        SFX(uplift_residual)(k, i, eta, &f, &fp);
        if (f < 0.0 && eta > lo)
            lo = eta;
        if (f > 0.0 && eta < hi)
            hi = eta;
        double step = -f / fp, nxt = eta + step;
        conv = fabs(step) <= par->step_tol || f == 0.0;
        if (!((nxt >= lo && nxt <= hi) || conv))
            nxt = isfinite(lo) ? 0.5 * (lo + hi) : eta - 4.0;
        if (f != 0.0)
            eta = nxt;
        k->iters[i] = it;
        if (conv)
            break;
    }
    k->d[i] = exp(eta);
    return conv;
}

/* a lane of tiny m = x/B (below TINY_M, hook tensions beyond T/w ~ 1e60 x): the start of
 * catenary._uplift_setup in d sc (no underflow of m^2), then the bracketed Newton with the
 * scaled residual; returns 1 if it converged */
static int SFX(uplift_tiny)(BLOCK_T *k, int i, const Params *par)
{
    double e = k->e[i], r02 = k->r02[i], x0 = k->x0[i], m = k->m[i];
    int ex;
    frexp(m, &ex);
    double sc = ldexp(1.0, -ex), ms = m * sc, r02s = r02 * sc;
    double xlo = log1p(e);
    double d_max = x0 - xlo;
    double c1 = x0 * x0 / (d_max * (r02 + d_max));
    double q = ms * ms / c1;
    double r02_sq = r02s * r02s;
    double d = 2.0 * q / (r02s + sqrt(r02_sq + 4.0 * q)) / sc;
    double frac = d / d_max;
    if (frac < 1.0) {
        double c0 = 2.0 * (1.0 + e) * xlo / r02;
        q = q * exp((frac - 1.0) * log(c0 * c0 / c1));
        d = 2.0 * q / (r02s + sqrt(r02_sq + 4.0 * q)) / sc;
    }
    d = d > 1e-300 ? d : 1e-300;
    d = d < d_max ? d : d_max;
    k->xlo[i] = xlo;
    k->d[i] = d;
    k->d0[i] = d;
    k->d_max[i] = d_max;
    return SFX(uplift_safeguarded)(k, i, 0, par);
}

/* a tiny lane's uplift state (catenary._lifted_from_d in plain libm: the block's form divides
 * by X^2, which underflows) */
static void SFX(tiny_state)(BLOCK_T *k, int i, int has_x)
{
    double w = k->w[i], h = k->h[i], b = k->b[i], e = k->e[i], m = k->m[i];
    double big_x = k->xlo[i] + k->d[i];
    double s = m / big_x; /* sech u */
    double half = sinh(0.5 * big_x), sx = sinh(big_x);
    double cm1 = 2.0 * half * half;
    double tu = (e - cm1) / sx;
    tu = tu > 0.0 ? tu : 0.0;
    double wb = w * b;
    k->o[O_R][i] = wb * s;
    k->o[O_F][i] = wb * tu;
    k->o[O_L][i] = b * (tu * cm1 + sx);
    k->o[O_ALPHA][i] = atan2(tu, s) * RAD2DEG;
    k->o[O_BETA][i] = atan2(tu * (1.0 + cm1) + sx, s) * RAD2DEG;
    k->o[O_TIDE][i] = has_x ? b * s * cm1 - h : NAN;
}

/* 6. of block: lanes of status 0 whose results are not all finite become OUT_OF_RANGE (the tide
 * and load margins may be +inf); then a grounded lane with x/a beyond exp's range (> 709.78),
 * whose cosh - 1 overflowed in 4., gets the finite a (cosh(x/a) - 1) that lasts up to
 * x/a ~ 710 + log(2/a) for a < 2 m: catenary.depth_reached's 2 a sinh(x/2a)^2 (+inf again
 * where that overflows) */
static void SFX(in_range)(BLOCK_T *k, int nb, const Params *par)
{
    const int has_x = par->has_x, has_mbl = par->has_mbl;
    for (int i = 0; i < nb; i++) {
        double *const *o = k->o;
        int fin = (fabs(o[O_R][i]) <= DBL_MAX) & (fabs(o[O_T][i]) <= DBL_MAX) &
                  (fabs(o[O_XMIN][i]) <= DBL_MAX) & (fabs(o[O_L][i]) <= DBL_MAX) &
                  (fabs(o[O_BETA][i]) <= DBL_MAX) & (fabs(o[O_ALPHA][i]) <= DBL_MAX) &
                  (fabs(o[O_F][i]) <= DBL_MAX);
        if (has_x)
            fin &= (fabs(o[O_AM][i]) <= DBL_MAX) & (o[O_TIDE][i] >= -DBL_MAX) &
                   (o[O_LOAD][i] >= -DBL_MAX);
        if (has_mbl)
            fin &= fabs(o[O_SF][i]) <= DBL_MAX;
        if (k->status[i] == 0 && !fin)
            k->status[i] = ST_OUT_OF_RANGE;
        if (o[O_TIDE][i] > DBL_MAX) {
            double half = sinh(0.5 * k->m[i]);
            o[O_TIDE][i] = 2.0 * k->b[i] * half * half - k->h[i];
        }
    }
}

/* a gathered lane's results back to its place in the block */
static inline void SFX(lane_home)(BLOCK_T *k, int j)
{
    int i = k->idx[j];
    k->xlo[i] = k->gxlo[j];
    k->d[i] = k->gd[j];
    k->d0[i] = k->gd0[j];
    k->d_max[i] = k->gdmax[j];
    k->iters[i] = k->giters[j];
    k->ldone[i] = k->gdone[j];
}

static void SFX(block)(BLOCK_T *restrict k, int nb, const Params *restrict par)
{
    const int has_x = par->has_x, has_mbl = par->has_mbl;
    const double tol = par->step_tol;
    int kfast = par->maxiter < KFAST ? par->maxiter : KFAST;
    if (kfast < 0)
        kfast = 0;
    double *restrict o_r = k->o[O_R], *restrict o_t = k->o[O_T], *restrict o_xmin = k->o[O_XMIN];
    double *restrict o_l = k->o[O_L], *restrict o_beta = k->o[O_BETA];
    double *restrict o_alpha = k->o[O_ALPHA], *restrict o_f = k->o[O_F];
    double *restrict o_am = k->o[O_AM], *restrict o_tide = k->o[O_TIDE];
    double *restrict o_load = k->o[O_LOAD], *restrict o_gl = k->o[O_GL];
    double *restrict o_sf = k->o[O_SF];

    /* 1. validation, the grounded chain (problems 1 and 3), the uplift start */
    const double *restrict s_w = k->src[0], *restrict s_h = k->src[1], *restrict s_t = k->src[2];
    const double *restrict s_x = k->src[3], *restrict s_mbl = k->src[4];
    /* odd: a sum of the outputs, finite unless one is inf or NaN (or the sum overflows): then
     * 6. classifies the lanes; m_min: the smallest m, for the tiny lanes */
    double odd = 0.0, m_min = INFINITY;
    CM_SIMD_WITH(reduction(+ : odd) reduction(min : m_min))
    for (int i = 0; i < nb; i++) {
        double w = s_w[i], h = s_h[i], t = s_t[i];
        double x = s_x[i], mbl = s_mbl[i]; /* 1.0 when not given */
        int fin = (fabs(w) <= DBL_MAX) & (fabs(h) <= DBL_MAX) & (fabs(t) <= DBL_MAX) &
                  (fabs(x) <= DBL_MAX) & (fabs(mbl) <= DBL_MAX);
        /* the first rule broken wins (Status order), written as selects */
        int st = !(mbl > 0.0) ? ST_MBL : 0;
        st = !(x > 0.0) ? ST_DISTANCE : st;
        st = !(t > w * h) ? ST_TENSION : st;
        st = !(h > 0.0) ? ST_DEPTH : st;
        st = !(w > 0.0) ? ST_WEIGHT : st;
        st = !fin ? ST_NON_FINITE : st;
        k->status[i] = st;
        /* invalid lanes compute a harmless stand-in scene; their outputs become NaN */
        w = st ? 1.0 : w;
        h = st ? 1.0 : h;
        t = st ? 4.0 : t;
        x = st ? 1.0 : x;
        k->w[i] = w;
        k->h[i] = h;
        k->t[i] = t;
        k->x[i] = x;
        double p = w * h;
        double b = ((t - p) - prod_err(w, h, p)) / w; /* anchor-end tension / w, compensated */
        double ib = 1.0 / b;
        double e = h * ib;
        double r02 = e * (2.0 + e);
        double sq = sqrt(r02);
        double x0 = log1p(e + sq); /* acosh(1 + e) */
        double xmin = b * x0;
        double m = x * ib;
        k->b[i] = b;
        k->e[i] = e;
        k->r02[i] = r02;
        k->x0[i] = x0;
        k->xlo[i] = 0.0; /* set for the lifted lanes below */
        k->d[i] = 0.0;
        k->m[i] = m;
        k->len[i] = b * sq; /* sqrt(h (h + 2b)) */
        int lift = (x < xmin) & has_x;
        k->lift[i] = lift;
        k->ldone[i] = !lift;
        k->iters[i] = 0;
        m_min = m < m_min ? m : m_min;
        double sf = mbl / t;
        odd += xmin + sf; /* x - xmin is finite with xmin */
        o_xmin[i] = xmin;
        o_t[i] = t;
        o_gl[i] = NAN;
        o_sf[i] = has_mbl ? sf : NAN;
        o_am[i] = has_x ? x - xmin : NAN;
    }

    /* the lifted lanes of tiny m leave lift[] (the vector Newton's lanes): solved one by one
     * in 3., their state by tiny_state */
    int ntiny = 0;
    for (int i = 0; m_min < TINY_M && i < nb; i++)
        if (k->lift[i] & (k->m[i] < TINY_M)) {
            k->lift[i] = 0;
            ntiny++;
        }

    /* 2. Newton in eta = log(d) on the lifted lanes, gathered densely, each frozen once its step
     *    is below tol; the step is applied as d *= exp(step) (a degree-6 Taylor polynomial: exact
     *    for the converging steps, positive for any step) */
    int nl = 0, ran = 0, pending = 0; /* pending: lanes the fast steps leave moving */
    if (has_x) {
        for (int i = 0; i < nb; i++) {
            k->idx[nl] = i;
            nl += k->lift[i];
        }
        /* the lanes being solved: gathered densely into the g arrays, or, when every lane of the
         * block is lifted (the sweep's blocks), the block's own arrays, until a compaction
         * gathers the lanes still moving */
        int inplace = nl == nb;
        double *ge = k->ge, *gr = k->gr, *gx0 = k->gx0, *gm = k->gm, *gxlo = k->gxlo;
        double *gd = k->gd, *gd0 = k->gd0, *gdmax = k->gdmax;
        int *gdone = k->gdone, *giters = k->giters;
        if (inplace) {
            ge = k->e, gr = k->r02, gx0 = k->x0, gm = k->m, gxlo = k->xlo;
            gd = k->d, gd0 = k->d0, gdmax = k->d_max, gdone = k->ldone, giters = k->iters;
        } else {
            for (int j = 0; j < nl; j++) {
                int i = k->idx[j];
                ge[j] = k->e[i];
                gr[j] = k->r02[i];
                gx0[j] = k->x0[i];
                gm[j] = k->m[i];
            }
            for (int j = nl; j < LANES(nl); j++) { /* stand-ins up to a whole vector */
                k->idx[j] = k->idx[0];
                ge[j] = ge[0];
                gr[j] = gr[0];
                gx0[j] = gx0[0];
                gm[j] = gm[0];
            }
        }
        int nlp = LANES(nl);
        /* start of the uplift solve (catenary._uplift_setup), in d = X - log1p(e) */
        CM_SIMD
        for (int j = 0; j < nlp; j++) {
            double e = ge[j], r02 = gr[j], x0 = gx0[j], m2 = gm[j] * gm[j];
            double xlo = log1p(e);
            double d_max = x0 - xlo;
            double inv = 1.0 / (x0 * r02);                     /* one division for two */
            double ix0 = r02 * inv, ir02 = x0 * inv;
            double ic1 = d_max * (r02 + d_max) * (ix0 * ix0); /* 1 / c1 */
            double q = m2 * ic1;
            double r02_sq = r02 * r02;
            /* d / d_max at the first root d = 2q / (r02 + sqrt(r02^2 + 4q)) */
            double frac = 2.0 * q / ((r02 + sqrt(r02_sq + 4.0 * q)) * d_max);
            frac = frac < 1.0 ? frac : 1.0;
            double c0 = 2.0 * (1.0 + e) * xlo * ir02;
            double q2 = q * exp((frac - 1.0) * log(c0 * c0 * ic1));
            double d = 2.0 * q2 / (r02 + sqrt(r02_sq + 4.0 * q2));
            d = d > 1e-300 ? d : 1e-300;
            d = d < d_max ? d : d_max;
            gxlo[j] = xlo;
            gd[j] = d;
            gd0[j] = d;
            gdmax[j] = d_max;
            gdone[j] = 0;
            giters[j] = 0;
        }
        for (int j = nl; j < nlp; j++)
            gdone[j] = 1; /* the stand-ins never move */
        int na = nl; /* the moving lanes: entries [0, na) */
        pending = nl;
        for (int it = 1; it <= kfast; it++) {
            int left = 0;
            int nap = LANES(na);
            CM_SIMD_REDUCTION(left)
            for (int j = 0; j < nap; j++) {
                double d = gd[j], e = ge[j], r02 = gr[j];
                double big_x = gxlo[j] + d;
                double em = expm1(d);
                double ed = 1.0 + em;
                double e1 = e + em * (1.0 + e); /* expm1(X): exp(X) = (1 + e) exp(d) */
                double g = 1.0 + e1;
                double rr = 1.0 / (ed * g);
                double ied = g * rr, ig = ed * rr;
                double p = r02 + em * ied;
                double sx = 0.5 * e1 * (1.0 + ig); /* sinh X */
                double cx = 0.5 * (g + ig);        /* cosh X */
                /* the residual log(A/B) of catenary._uplift_residual, as 2 (A - B)/(A + B) =
                 * 2 tanh(log(A/B)/2): the same root and slope there, no log to evaluate */
                double ra = em * p * (big_x * big_x), rb = (gm[j] * gm[j]) * (sx * sx);
                /* d/dd of the residual: exp(d)/expm1(d) + 1/(exp(d) p) - 2 (coth X - 1/X),
                 * over one denominator; step = -f / (d * that), one division for both */
                double den1 = em * ed * p, den2 = sx * big_x;
                double num = (ed * ed * p + em) * den2 - 2.0 * (cx * big_x - sx) * den1;
                double step = -2.0 * (ra - rb) * den1 * den2 / ((ra + rb) * num * d);
                double f = ra - rb; /* only its sign and zero matter below */
                double ex = 1.0 + step * (1.0 + step * (0.5 + step * (1.0 / 6.0 +
                            step * (1.0 / 24.0 + step * (1.0 / 120.0 + step * (1.0 / 720.0))))));
                double nxt = d * ex;
                nxt = nxt < gdmax[j] ? nxt : gdmax[j];
                int was = gdone[j];
                int conv = (fabs(step) <= tol) | (f == 0.0);
                double keep = f == 0.0 ? d : nxt;
                gd[j] = was ? d : keep;
                giters[j] = was ? giters[j] : it;
                gdone[j] = was | conv;
                left += !(was | conv);
            }
            ran = it;
            pending = left;
            if (!left)
                break;
            if (left * 2 <= na) { /* compact: the done lanes go home, the moving ones first */
                int q = 0;
                for (int j = 0; j < na; j++) {
                    if (gdone[j]) {
                        if (!inplace)
                            SFX(lane_home)(k, j);
                        continue;
                    }
                    k->idx[q] = k->idx[j];
                    k->ge[q] = ge[j];
                    k->gr[q] = gr[j];
                    k->gx0[q] = gx0[j];
                    k->gxlo[q] = gxlo[j];
                    k->gm[q] = gm[j];
                    k->gd[q] = gd[j];
                    k->gd0[q] = gd0[j];
                    k->gdmax[q] = gdmax[j];
                    k->giters[q] = giters[j];
                    k->gdone[q] = 0;
                    q++;
                }
                na = q;
                inplace = 0;
                ge = k->ge, gr = k->gr, gx0 = k->gx0, gm = k->gm, gxlo = k->gxlo;
                gd = k->gd, gd0 = k->gd0, gdmax = k->gdmax, gdone = k->gdone, giters = k->giters;
                for (int j = na; j < LANES(na); j++) { /* stand-ins again: copies of lane 0 */
                    ge[j] = ge[0];
                    gr[j] = gr[0];
                    gxlo[j] = gxlo[0];
                    gm[j] = gm[0];
                    gd[j] = gd[0];
                    gdmax[j] = gdmax[0];
                    giters[j] = 0;
                    gdone[j] = 1;
                }
            }
        }
        if (!inplace)
            for (int j = 0; j < na; j++)
                SFX(lane_home)(k, j);
    }
    /* 3. the few lanes still moving: bracketed Newton, one at a time */
    int failed = 0;
    if (pending | ntiny)
        for (int i = 0; i < nb; i++)
            if (!k->ldone[i]) {
                k->ldone[i] = k->lift[i] ? SFX(uplift_safeguarded)(k, i, ran, par)
                                         : SFX(uplift_tiny)(k, i, par); /* a tiny lane */
                failed += !k->ldone[i];
            }

    /* 4. uplift state, margins and the load-margin solve from its table start (a tiny lane is
     *    computed as grounded here, then by tiny_state) */
    CM_SIMD_REDUCTION(odd)
    for (int i = 0; i < nb; i++) {
        double w = k->w[i], h = k->h[i], b = k->b[i], e = k->e[i], m = k->m[i];
        int lift = k->lift[i];
        double xt = lift ? k->xlo[i] + k->d[i] : m; /* X, or x / a for a grounded chain */
        double et = expm1(xt);
        double g = 1.0 + et;
        double rr = 1.0 / (g * xt * et * (g + 1.0));
        /* 1 / g; 0 where the shared denominator overflows (x/a > ~352, only grounded lanes get
         * there: a lifted X is below acosh(1 + 2^53)): 1/g < 1e-153 then, nothing next to 1 in
         * sinh and cosh - 1, where inf * 0 made them NaN (the grounded tide margin) */
        double ig = rr > 0.0 ? xt * et * (g + 1.0) * rr : 0.0;
        double isx = 2.0 * g * g * xt * rr;   /* 1 / sinh */
        double sx = 0.5 * et * (1.0 + ig);    /* sinh */
        double cm1 = et < 1.0 ? 0.5 * et * et * ig : 0.5 * et * (1.0 - ig); /* cosh - 1 */
        double s = lift ? m * (g * et * (g + 1.0) * rr) : 1.0; /* sech u = m / X */
        double tu = (e - cm1) * isx;          /* tanh u */
        tu = lift ? (tu > 0.0 ? tu : 0.0) : 0.0;
        double wb = w * b;
        double r = wb * s;
        double len = k->len[i];
        double l = lift ? b * (tu * cm1 + sx) : len, f = wb * tu;
        double tide = b * s * cm1 - h; /* a (cosh(x/a) - 1) - h, a = R/w */
        /* the angles need no term: atan2 is NaN only for a NaN argument, and then r, l or f
         * is not finite (tu is never NaN) */
        odd += r + l + f + tide;
        o_r[i] = r;
        o_l[i] = l;
        o_f[i] = f;
        o_tide[i] = has_x ? tide : NAN;
        o_beta[i] = atan2(lift ? tu * (1.0 + cm1) + sx : len, lift ? s : b) * RAD2DEG;
        o_alpha[i] = atan2(tu, s) * RAD2DEG;
    }
    for (int i = 0; ntiny && i < nb; i++)
        if (k->lift[i] < ((k->x[i] < o_xmin[i]) & has_x)) /* lifted, not in lift[]: tiny */
            SFX(tiny_state)(k, i, has_x);
    int nodd = ntiny; /* tiny_state's values are not in odd */
    if (has_x) {
        int nscalar = 0;
        CM_SIMD_REDUCTION(nscalar, odd)
        for (int i = 0; i < nb; i++) {
            /* load margin: a_crit from the fine table (exact to ~1e-14 inside it) */
            double h = k->h[i], x = k->x[i];
            double c = h / x;
            double log_c = log(c);
            double pos = (log_c - TAB.y0) * TAB.inv_dy;
            int inside = (pos >= 0.0) & (pos < (double)TAB.n);
            int j = (int)(inside ? pos : 0.0);
            double tt = pos - j;
            const double *restrict tab = TAB.data;
            int j2 = 2 * j;
            double y0 = tab[j2], s0 = tab[j2 + 1], y1 = tab[j2 + 2], s1 = tab[j2 + 3];
            double ce = y0 + tt * (s0 + tt * ((3.0 * (y1 - y0) - 2.0 * s0 - s1) +
                                              tt * (2.0 * (y0 - y1) + s0 + s1)));
            double a_crit = 0.5 * x * exp(-ce); /* no division */
            int cok = inside & (par->maxiter >= 1);
            k->cok[i] = cok;
            nscalar += !cok;
            double load = k->w[i] * (a_crit + h) - k->t[i];
            odd += load;
            o_load[i] = load;
        }
        /* 5. load-margin lanes outside the table or not converged: the scalar solve */
        for (int i = 0; nscalar && i < nb; i++)
            if (!k->cok[i] && !k->status[i]) {
                double a_crit = critical_scalar(k->h[i], k->x[i], par);
                o_load[i] = k->w[i] * (a_crit + k->h[i]) - k->t[i];
                nodd += !(o_load[i] - o_load[i] == 0.0);
                if (a_crit != a_crit)
                    k->status[i] = ST_NO_CONVERGENCE;
            }
        for (int i = 0; failed && i < nb; i++)
            if (!k->ldone[i] && !k->status[i])
                k->status[i] = ST_NO_CONVERGENCE;
    } else
        for (int i = 0; i < nb; i++)
            o_load[i] = NAN;

    /* 6. never status 0 with a value that is not finite: a solved lane whose results (those
     *    that apply) under- or overflowed is beyond float64 range (Status.OUT_OF_RANGE); the
     *    exceptions are the tide and load margins at +inf (result.INF_MARGINS): a grounded
     *    chain's a (cosh(x/a) - 1) or critical tension beyond float64, real margins no tide or
     *    load reaches.  Only in blocks whose odd is not finite or with a lane in nodd (rare:
     *    extreme scenes) */
    if (nodd | !(odd - odd == 0.0))
        SFX(in_range)(k, nb, par);
}
