/* One block of problem 3/4 lanes (see _kernels.c).  Included once per instruction set with
 * SFX(name) giving the suffixed name; every loop over lanes is a `#pragma omp simd` loop whose
 * body is straight-line code with selects, so GCC vectorizes it with glibc's libmvec. */

static void SFX(block)(Block *restrict k, int nb, const Params *restrict par)
{
    const int has_x = par->has_x, has_mbl = par->has_mbl;
    const double tol = par->step_tol;
    int kfast = par->maxiter < KFAST ? par->maxiter : KFAST;
    if (kfast < 0)
        kfast = 0;

    /* 1. validation, the grounded chain (problems 1 and 3), the uplift start */
#pragma omp simd
    for (int i = 0; i < nb; i++) {
        double w = k->w[i], h = k->h[i], t = k->t[i];
        double x = k->x[i], mbl = k->mbl[i]; /* 1.0 when not given */
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
        double e = h / b;
        double r02 = e * (2.0 + e);
        double sq = sqrt(r02);
        double x0 = log1p(e + sq); /* acosh(1 + e) */
        double xmin = b * x0;
        k->b[i] = b;
        k->e[i] = e;
        k->r02[i] = r02;
        k->xmin[i] = xmin;
        k->len[i] = sqrt(h * (h + 2.0 * b));
        int lift = (x < xmin) & has_x;
        k->lift[i] = lift;
        /* start of the uplift solve (catenary._uplift_setup) */
        double xlo = log1p(e);
        double m = x / b;
        double d_max = x0 - xlo;
        double c1 = x0 * x0 / (d_max * (r02 + d_max));
        double q = m * m / c1;
        double r02_sq = r02 * r02;
        double d = 2.0 * q / (r02 + sqrt(r02_sq + 4.0 * q));
        double frac = d / d_max;
        frac = frac < 1.0 ? frac : 1.0;
        double c0 = 2.0 * (1.0 + e) * xlo / r02;
        double q2 = q * exp((frac - 1.0) * log(c0 * c0 / c1));
        d = 2.0 * q2 / (r02 + sqrt(r02_sq + 4.0 * q2));
        double eta_hi = log(d_max);
        double eta = log(d > 1e-300 ? d : 1e-300);
        eta = eta < eta_hi ? eta : eta_hi;
        k->xlo[i] = xlo;
        k->m[i] = m;
        k->eta[i] = eta;
        k->start[i] = eta;
        k->eta_hi[i] = eta_hi;
        k->done[i] = !lift;
        k->iters[i] = 0;
    }

    /* 2. Newton in eta = log(d) on every lifted lane, frozen once its step is below tol */
    if (has_x) {
        for (int it = 1; it <= kfast; it++) {
            int left = 0;
#pragma omp simd reduction(+ : left)
            for (int i = 0; i < nb; i++) {
                double eta = k->eta[i], e = k->e[i], r02 = k->r02[i];
                double xlo = k->xlo[i], m = k->m[i];
                double d = exp(eta);
                double big_x = xlo + d;
                double em = expm1(d);
                double ed = 1.0 + em;
                double p = r02 + em / ed;
                double e1 = e + em * (1.0 + e); /* expm1(X): exp(X) = (1 + e) exp(d) */
                double g = 1.0 + e1;
                double ig = 1.0 / g;
                double sx = 0.5 * e1 * (1.0 + ig); /* sinh X */
                double cx = 0.5 * (g + ig);        /* cosh X */
                double qq = big_x / (m * sx);
                double f = log(em * p * (qq * qq));
                double fp = (ed / em + 1.0 / (ed * p) - 2.0 * (cx / sx - 1.0 / big_x)) * d;
                double step = -f / fp;
                double nxt = eta + step;
                nxt = nxt < k->eta_hi[i] ? nxt : k->eta_hi[i];
                int was = k->done[i];
                int conv = (fabs(step) <= tol) | (f == 0.0);
                double keep = f == 0.0 ? eta : nxt;
                k->eta[i] = was ? eta : keep;
                k->iters[i] = was ? k->iters[i] : it;
                k->done[i] = was | conv;
                left += !(was | conv);
            }
            if (!left)
                break;
        }
        /* 3. the few lanes still moving: bracketed Newton, one lane at a time */
        for (int i = 0; i < nb; i++)
            if (!k->done[i])
                uplift_safeguarded(k, i, kfast, par);
    }

    /* 4. uplift state, margins and the load-margin solve from its table start */
#pragma omp simd
    for (int i = 0; i < nb; i++) {
        double w = k->w[i], h = k->h[i], t = k->t[i], x = k->x[i], b = k->b[i];
        double xmin = k->xmin[i], e = k->e[i];
        int lift = k->lift[i];
        double big_x = k->xlo[i] + exp(k->eta[i]);
        double xt = lift ? big_x : k->m[i];
        double et = expm1(xt);
        double g = 1.0 + et;
        double sx = 0.5 * et * (1.0 + 1.0 / g); /* sinh */
        double cm1 = 0.5 * et * et / g;          /* cosh - 1 */
        double s = lift ? k->m[i] / big_x : 1.0; /* sech u */
        double tu = (e - cm1) / sx;              /* tanh u */
        tu = lift ? (tu > 0.0 ? tu : 0.0) : 0.0;
        double wb = w * b;
        double r = wb * s;
        double len = lift ? b * (tu * cm1 + sx) : k->len[i];
        double by = lift ? tu * (1.0 + cm1) + sx : k->len[i];
        double bx = lift ? s : b;
        k->o[O_R][i] = r;
        k->o[O_T][i] = t;
        k->o[O_XMIN][i] = xmin;
        k->o[O_L][i] = len;
        k->o[O_BETA][i] = atan2(by, bx) * RAD2DEG;
        k->o[O_ALPHA][i] = atan2(tu, s) * RAD2DEG;
        k->o[O_F][i] = wb * tu;
        k->o[O_SF][i] = k->mbl[i] / t;
        k->o[O_GL][i] = NAN;
        /* load margin: a_crit from the Hermite table start and one Newton residual */
        double c = h / x;
        double log_c = log(c);
        double pos = (log_c - TAB.y0) * TAB.inv_dy;
        int inside = (pos >= 0.0) & (pos < (double)TAB.n);
        int j = (int)(inside ? pos : 0.0);
        double tt = pos - j;
        double y0 = TAB.eta[j], y1 = TAB.eta[j + 1], s0 = TAB.slope[j], s1 = TAB.slope[j + 1];
        double ce = y0 + tt * (s0 + tt * ((3.0 * (y1 - y0) - 2.0 * s0 - s1) +
                                          tt * (2.0 * (y0 - y1) + s0 + s1)));
        double cd = exp(ce);
        double em2 = expm1(-2.0 * cd);
        double cf = 2.0 * (cd + log(-em2) - LOG_2) - ce - log_c;
        double cfp = 2.0 * cd * (2.0 + em2) / (-em2) - 1.0; /* 2 D / tanh D - 1 */
        double cstep = -cf / cfp;
        cstep = cstep > 4.0 ? 4.0 : (cstep < -4.0 ? -4.0 : cstep);
        ce += cstep;
        double a_crit = x / (2.0 * exp(ce));
        k->cok[i] = inside & (fabs(cstep) <= tol) & (par->maxiter >= 1);
        k->o[O_AM][i] = x - xmin;
        k->o[O_TIDE][i] = (r / w) * cm1 - h;
        k->o[O_LOAD][i] = w * (a_crit + h) - t;
    }

    if (!has_x)
        for (int i = 0; i < nb; i++)
            k->o[O_AM][i] = k->o[O_TIDE][i] = k->o[O_LOAD][i] = NAN;
    if (!has_mbl)
        for (int i = 0; i < nb; i++)
            k->o[O_SF][i] = NAN;

    /* 5. load-margin lanes outside the table or not converged: the scalar solve */
    if (has_x)
        for (int i = 0; i < nb; i++)
            if (!k->cok[i] && !k->status[i]) {
                double a_crit = critical_scalar(k->h[i], k->x[i], par);
                k->o[O_LOAD][i] = k->w[i] * (a_crit + k->h[i]) - k->t[i];
                if (a_crit != a_crit)
                    k->status[i] = ST_NO_CONVERGENCE;
            }
    for (int i = 0; i < nb; i++)
        if (has_x && !k->done[i] && !k->status[i])
            k->status[i] = ST_NO_CONVERGENCE;
}
