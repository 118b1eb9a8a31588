/*
 * skysh {{VERSION}}: SH lighting of the Hosek-Wilkie (2012) sky, per frame, in C99
 * (skysh.export.hosek.export_source("c", bands=SKYSH_HW_BANDS, accuracy="{{ACCURACY}}"); do not edit).
 *
 * The numbers of skysh.model.hosek_frame.coefficients (linear sRGB, the RGB dataset) and of the runtime's
 * post steps (skysh.SkySH.load(model="hosek-wilkie").coefficients), computed from the exact model on a
 * sun-adapted product rule every frame. A header: #include it in any number of C or C++ files and link
 * with -lm. Every function is static inline, every table static const; nothing is allocated.
 *
 *   static skysh_hw_state state;                  // 12 KB (3 bands) to 18 KB (7): nodes, scratch
 *   if (skysh_hw_init(&state, bands) != 0) ...    // once: bands in [1, SKYSH_HW_BANDS]
 *   double albedo[3] = {0.3, 0.3, 0.3}, out[SKYSH_HW_COUNT * 3];
 *   int rc = skysh_hw_coefficients(&state, sun_zenith, turbidity, sun_azimuth, albedo,
 *                                  SKYSH_HW_RADIANCE_DEFAULT, out);   // per frame
 *
 * skysh_hw_coefficients writes bands * bands RGB coefficients, out[3 i + c], i = l (l + 1) + m: real
 * orthonormal SH with the Condon-Shortley phase, Z up, azimuth from +X towards +Y, radians; cd/m^2
 * (irradiance: cd/m^2 x sr). flags: SKYSH_HW_GIBBS (the zonal filter sinc(pi l / N), Habel 2008 eq. 5),
 * SKYSH_HW_DERING (the least window keeping the irradiance non-negative, Sloan 2017, as
 * skysh.post.dering.dering(c, "irradiance"); at bands == SKYSH_HW_BANDS only), SKYSH_HW_IRRADIANCE (times
 * the clamped-cosine lobe A_l), in that order; the runtime's defaults are SKYSH_HW_RADIANCE_DEFAULT
 * (gibbs) and SKYSH_HW_IRRADIANCE_DEFAULT (irradiance, dering). albedo: the ground albedo per channel
 * (R, G, B), each in [0, 1], NULL for 0. Returns 0, or 1 when the deringing found no non-negative window
 * (its last row applied, as Python, which warns), or a negative code with out zeroed: -1 sun zenith
 * outside [0, pi/2], -2 turbidity outside [1, 10], -3 an albedo outside [0, 1], -4 a non-finite azimuth,
 * -5 dering asked at fewer bands than SKYSH_HW_BANDS, -6 unknown flags; -7 a state not initialised (out
 * untouched: its length is unknown).
 * skysh_hw_configuration gives the model's parameters (eq. 9) at a sun position, skysh_hw_radiance the
 * sky's radiance in one direction. Also compiles as C++ (g++ -std=c++11 -pedantic).
 *
 * The rule (skysh.model.hosek_frame): zenith panels {0, the sun's zenith, 45, 85, 90} degrees,
 * Gauss-Legendre in theta below 45 degrees and in u = sqrt(cos theta) above, the fixed panel holding the
 * sun with SKYSH_HW_SUN more nodes shared by the widths of its two sides (at least SKYSH_HW_MINIMUM a
 * side); azimuth Gauss-Legendre on [0, pi] (SKYSH_HW_AZIMUTH nodes, SKYSH_HW_LOW_SUN_AZIMUTH past 80
 * degrees). skysh_hw_init computes the Gauss-Legendre nodes and weights of every count by Newton's method
 * on the Legendre recurrence (full double precision) and the azimuth moments' factors cos(m phi) w pi.
 * Not thread-safe per state (one state per thread; the deringing keeps a static buffer at 5..7 bands).
 *
 * The dataset's notice (its tables below are Hosek and Wilkie's RGB dataset, as shipped with skysh):
 *
{{LICENSE}}
 */
#ifndef SKYSH_HOSEK_WILKIE_H
#define SKYSH_HOSEK_WILKIE_H

#include <math.h>

#define SKYSH_FLOAT 0 /* the deringing's words: double */
{{DEFINES}}
#define SKYSH_HW_GIBBS 1
#define SKYSH_HW_DERING 2
#define SKYSH_HW_IRRADIANCE 4
#define SKYSH_HW_RADIANCE_DEFAULT SKYSH_HW_GIBBS
#define SKYSH_HW_IRRADIANCE_DEFAULT (SKYSH_HW_IRRADIANCE | SKYSH_HW_DERING)
#define SKYSH_HW_MAGIC 0x48573132

/* Parameters A, B, C, D, E, F, G, I, H (the dataset's order) at [((((t * 2 + a) * 6 + k) * 3 + c) * 9 + p]:
 * turbidity 1..10, albedo 0 and 1, Bezier control point k (0: sun on the horizon), channel R, G, B. */
static const double SKYSH_HW_PARAMS[10 * 2 * 6 * 3 * 9] = {
    {{PARAMS}}
};
/* The channels' mean radiance L_M (dataset units: x SKYSH_HW_EFFICACY = cd/m^2) at [(((t * 2 + a) * 6 + k) * 3 + c]. */
static const double SKYSH_HW_RADIANCES[10 * 2 * 6 * 3] = {
    {{RADIANCES}}
};
/* Chebyshev rows of n bands at offset sum_{k<n} k^3: Y_l|m|(theta, 0) = sin^|m| theta sum_k c[k n^2 + i] cos(k theta). */
static const double SKYSH_HW_CHEBYSHEV[SKYSH_HW_CHEBYSHEV_SIZE] = {
    {{CHEBYSHEV}}
};
/* The Gibbs factors sinc(pi l / n) of n bands at offset n (n - 1) / 2. */
static const double SKYSH_HW_GIBBS_FACTORS[SKYSH_HW_GIBBS_SIZE] = {
    {{GIBBS}}
};
/* The clamped-cosine lobe A_l. */
static const double SKYSH_HW_LOBE[SKYSH_HW_BANDS] = {
    {{LOBE}}
};
static const int SKYSH_HW_M_OF[SKYSH_HW_COUNT] = {SKYSH_HW_M}; /* |m| of index i */
static const double SKYSH_HW_BEZIER_BINOMIALS[6] = {SKYSH_HW_BEZIER};

/* The deringing of SKYSH_HW_BANDS bands: skysh.export.dering.dering_source("c", "irradiance", "skysh_hw_dering"). */
{{DERING}}

#define SKYSH_HW_NODE_TABLE (SKYSH_HW_MAX_NODES * (SKYSH_HW_MAX_NODES + 1) / 2)

/* The state: the rule's standard nodes (built once by skysh_hw_init) and the per-frame scratch. */
typedef struct skysh_hw_state {
    int magic, bands;
    double gl_x[SKYSH_HW_NODE_TABLE], gl_w[SKYSH_HW_NODE_TABLE]; /* n nodes at n (n - 1) / 2, ascending */
    double az_sums[2][SKYSH_HW_MAX_AZIMUTH * SKYSH_HW_BANDS];   /* pi w_j cos(m phi_j): normal, low sun */
    double az_half[2][SKYSH_HW_MAX_AZIMUTH];                     /* sin^2(phi_j / 2) */
    double theta[SKYSH_HW_RINGS], cos_t[SKYSH_HW_RINGS], sqrt_cos[SKYSH_HW_RINGS], weight[SKYSH_HW_RINGS];
    double moments[SKYSH_HW_RINGS * 3 * SKYSH_HW_BANDS];        /* radial x azimuth moment m, [(r 3 + c) N + m] */
    double rows[SKYSH_HW_COUNT];
    double sh[SKYSH_HW_COUNT][3];
} skysh_hw_state;

/* Gauss-Legendre nodes (ascending) and weights of n points on [-1, 1]: Newton's method on the Legendre
 * recurrence from cos(pi (i + 3/4) / (n + 1/2)) until the step is below an ulp, then numpy's leggauss
 * symmetrisation and normalisation (weights summing to 2). */
static inline void skysh_hw_gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < (n + 1) / 2; i++) {
        double z = cos(SKYSH_HW_PI * ((double)i + 0.75) / ((double)n + 0.5)), p = 1.0, q = 0.0, d = 0.0;
        for (int it = 0; it < 100; it++) {
            p = 1.0;
            q = 0.0;
            for (int j = 1; j <= n; j++) { /* p = P_n(z), q = P_(n-1)(z) */
                const double r = q;
                q = p;
                p = ((2.0 * j - 1.0) * z * q - (j - 1.0) * r) / (double)j;
            }
            d = (double)n * (z * p - q) / (z * z - 1.0); /* P_n'(z) */
            const double step = p / d;
            z -= step;
            if (fabs(step) <= 1e-17 + 2e-16 * fabs(z) && it > 0) { break; }
        }
        p = 1.0;
        q = 0.0;
        for (int j = 1; j <= n; j++) {
            const double r = q;
            q = p;
            p = ((2.0 * j - 1.0) * z * q - (j - 1.0) * r) / (double)j;
        }
        d = (double)n * (z * p - q) / (z * z - 1.0);
        if (2 * i + 1 == n) { z = 0.0; }
        x[n - 1 - i] = z;
        x[i] = -z;
        w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z) * (1.0 + z) * d * d);
    }
    double total = 0.0;
    for (int i = 0; i < n; i++) { total += w[i]; }
    for (int i = 0; i < n; i++) { w[i] *= 2.0 / total; }
}

/* Build the rule's nodes for `bands` bands (in [1, SKYSH_HW_BANDS]); 0, or -7 (state NULL or bands out of range). */
static inline int skysh_hw_init(skysh_hw_state *state, int bands)
{
    if (!state) { return -7; }
    state->magic = 0;
    if (bands < 1 || bands > SKYSH_HW_BANDS) { return -7; }
    for (int n = 1; n <= SKYSH_HW_MAX_NODES; n++) {
        skysh_hw_gauss_legendre(n, state->gl_x + n * (n - 1) / 2, state->gl_w + n * (n - 1) / 2);
    }
    for (int low = 0; low < 2; low++) {
        const int n = low ? SKYSH_HW_LOW_SUN_AZIMUTH : SKYSH_HW_AZIMUTH;
        const double *x = state->gl_x + n * (n - 1) / 2, *w = state->gl_w + n * (n - 1) / 2;
        for (int j = 0; j < n; j++) {
            const double phi = SKYSH_HW_HALF_PI * (x[j] + 1.0), s = sin(0.5 * phi);
            state->az_half[low][j] = s * s;
            for (int m = 0; m < bands; m++) { state->az_sums[low][j * bands + m] = SKYSH_HW_PI * w[j] * cos(phi * (double)m); }
        }
    }
    state->bands = bands;
    state->magic = SKYSH_HW_MAGIC;
    return 0;
}

/* 0, or the code of the first parameter outside its domain (see the header). */
static inline int skysh_hw_check(double sun_zenith, double turbidity, double sun_azimuth, const double *albedo)
{
    if (!(sun_zenith >= SKYSH_HW_ZMIN && sun_zenith <= SKYSH_HW_ZMAX)) { return -1; }
    if (!(turbidity >= SKYSH_HW_TMIN && turbidity <= SKYSH_HW_TMAX)) { return -2; }
    for (int c = 0; albedo && c < 3; c++) {
        if (!(albedo[c] >= SKYSH_HW_AMIN && albedo[c] <= SKYSH_HW_AMAX)) { return -3; }
    }
    if (!isfinite(sun_azimuth)) { return -4; }
    return 0;
}

/* The parameters of each channel at a checked sun (Hosek and Wilkie 2012, section 5; skysh.model.hosek._interpolate):
 * params[10 c + p], p = A, B, C, D, E, F, G, I, H (the dataset's order) then L_M. */
static inline void skysh_hw_parameters(double ts, double t, const double *albedo, double params[30])
{
    const double u = t - 1.0;
    const int low = (int)fmin(floor(u), 8.0);
    const double frac = u - (double)low;
    const double x = cbrt(fmin(fmax(1.0 - ts / SKYSH_HW_HALF_PI, 0.0), 1.0));
    double bezier[6];
    for (int k = 0; k < 6; k++) { bezier[k] = SKYSH_HW_BEZIER_BINOMIALS[k] * pow(x, (double)k) * pow(1.0 - x, (double)(5 - k)); }
    for (int c = 0; c < 3; c++) {
        const double a = albedo ? albedo[c] : 0.0;
        for (int p = 0; p < 10; p++) {
            double sum = 0.0;
            for (int k = 0; k < 6; k++) {
                double v[2];
                for (int g = 0; g < 2; g++) {
                    const int i0 = ((low * 2 + g) * 6 + k) * 3 + c, i1 = (((low + 1) * 2 + g) * 6 + k) * 3 + c;
                    const double d0 = p < 9 ? SKYSH_HW_PARAMS[i0 * 9 + p] : SKYSH_HW_RADIANCES[i0];
                    const double d1 = p < 9 ? SKYSH_HW_PARAMS[i1 * 9 + p] : SKYSH_HW_RADIANCES[i1];
                    v[g] = (1.0 - frac) * d0 + frac * d1;
                }
                const double by_albedo = (1.0 - a) * v[0] + a * v[1];
                sum = k == 0 ? bezier[k] * by_albedo : sum + bezier[k] * by_albedo;
            }
            params[10 * c + p] = sum;
        }
    }
}

/* The model's parameters at a sun position (eq. 9 takes them): params[10 c + p] for channel c (R, G, B),
 * p = A, B, C, D, E, F, G, I, H (the dataset's order) then L_M (dataset units; x SKYSH_HW_EFFICACY = cd/m^2).
 * albedo: per channel or NULL (0). Returns 0, or -1 .. -3 (params zeroed). */
static inline int skysh_hw_configuration(double sun_zenith, double turbidity, const double *albedo, double params[30])
{
    const int rc = skysh_hw_check(sun_zenith, turbidity, 0.0, albedo);
    if (rc != 0) {
        for (int k = 0; k < 30; k++) { params[k] = 0.0; }
        return rc;
    }
    skysh_hw_parameters(sun_zenith, turbidity, albedo, params);
    return 0;
}

/* The sky's radiance, cd/m^2 (linear sRGB), at the unit direction dir (Z up): eq. 9 times L_M times
 * SKYSH_HW_EFFICACY, 0 below the horizon (dir[2] < 0); gamma = atan2(|d x s|, d . s) as skysh.model.hosek.
 * Returns 0, or -1 .. -4 (rgb zeroed). */
static inline int skysh_hw_radiance(const double dir[3], double sun_zenith, double turbidity, double sun_azimuth,
                                    const double *albedo, double rgb[3])
{
    double params[30];
    const int rc = skysh_hw_check(sun_zenith, turbidity, sun_azimuth, albedo);
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (rc != 0 || dir[2] < 0.0) { return rc; }
    skysh_hw_parameters(sun_zenith, turbidity, albedo, params);
    const double phi = fmod(sun_azimuth, SKYSH_HW_TWO_PI), s = sin(sun_zenith);
    const double sun[3] = {s * cos(phi), s * sin(phi), cos(sun_zenith)};
    const double cx = dir[1] * sun[2] - dir[2] * sun[1], cy = dir[2] * sun[0] - dir[0] * sun[2];
    const double cz = dir[0] * sun[1] - dir[1] * sun[0];
    const double gamma = atan2(sqrt(cx * cx + cy * cy + cz * cz), dir[0] * sun[0] + dir[1] * sun[1] + dir[2] * sun[2]);
    const double ct = dir[2], cg = cos(gamma);
    for (int c = 0; c < 3; c++) {
        const double *p = params + 10 * c;
        const double chi = (1.0 + cg * cg) / pow(1.0 + p[8] * p[8] - 2.0 * p[8] * cg, 1.5);
        const double f = (1.0 + p[0] * exp(p[1] / (ct + SKYSH_HW_HORIZON_OFFSET)))
                         * (p[2] + p[3] * exp(p[4] * gamma) + p[5] * cg * cg + p[6] * chi + p[7] * sqrt(ct));
        rgb[c] = SKYSH_HW_EFFICACY * (f * p[9]);
    }
    return 0;
}

/* The rings of the sun ts (skysh.model.hosek_frame._key, _layout, _rings) into the state; returns whether the sun is low. */
static inline int skysh_hw_rings(skysh_hw_state *s, double ts)
{
    static const double EDGES[4] = {0.0, SKYSH_HW_EDGE1, SKYSH_HW_EDGE2, SKYSH_HW_EDGE3};
    const int zenith[3] = {SKYSH_HW_ZENITH0, SKYSH_HW_ZENITH1, SKYSH_HW_ZENITH2};
    int below = 0; /* bisect_left: the edges below ts */
    while (below < 4 && EDGES[below] < ts) { below++; }
    const int panel = below > 1 ? below - 1 : 0;
    const double low = EDGES[panel], high = EDGES[panel + 1];
    const int total = zenith[panel] + SKYSH_HW_SUN;
    int upper;
    if (ts <= low || ts >= high) {
        upper = ts <= low ? 0 : total;
    } else { /* Python's round: half to even (nearbyint in the default rounding mode) */
        const int share = (int)nearbyint((double)total * ((ts - low) / (high - low)));
        upper = share < SKYSH_HW_MINIMUM ? SKYSH_HW_MINIMUM : share;
        upper = upper > total - SKYSH_HW_MINIMUM ? total - SKYSH_HW_MINIMUM : upper;
    }
    int counts[4];
    double edges[5];
    for (int k = 0; k < 4; k++) { /* the fixed panels, the sun's split in two */
        counts[k] = k < panel ? zenith[k] : k == panel ? upper : k == panel + 1 ? total - upper : zenith[k - 1];
    }
    for (int k = 0; k < 5; k++) { edges[k] = k <= panel ? EDGES[k] : k == panel + 1 ? ts : EDGES[k - 1]; }
    const int first_u = panel == 0 ? 2 : 1;
    int r = 0;
    for (int k = 0; k < 4; k++) {
        const int n = counts[k];
        if (n == 0) { continue; }
        const double *x = s->gl_x + n * (n - 1) / 2, *w = s->gl_w + n * (n - 1) / 2;
        const double lo = edges[k], hi = edges[k + 1];
        const double u_low = hi >= SKYSH_HW_HALF_PI ? 0.0 : sqrt(cos(hi)), u_high = sqrt(cos(lo));
        for (int q = 0; q < n; q++, r++) {
            const double node = 0.5 * (x[q] + 1.0), weight = 0.5 * w[q];
            if (k >= first_u) {
                const double u = u_low + (u_high - u_low) * node, ct = u * u;
                s->cos_t[r] = ct;
                s->theta[r] = acos(fmin(ct, 1.0));
                s->weight[r] = weight * ((u_high - u_low) * 2.0 * u);
            } else {
                const double theta = lo + (hi - lo) * node;
                s->theta[r] = theta;
                s->cos_t[r] = cos(theta);
                s->weight[r] = weight * ((hi - lo) * sin(theta));
            }
            s->sqrt_cos[r] = sqrt(s->cos_t[r]);
        }
    }
    return ts > SKYSH_HW_LOW_SUN;
}

/* The sky's radiance SH at a checked sun into s->sh (skysh.model.hosek_frame._project, then x SKYSH_HW_EFFICACY). */
static inline void skysh_hw_project(skysh_hw_state *s, double ts, double t, double phi_s, const double *albedo)
{
    const int n = s->bands, count = n * n;
    double params[30];
    skysh_hw_parameters(ts, t, albedo, params);
    const int low_sun = skysh_hw_rings(s, ts);
    const int nj = low_sun ? SKYSH_HW_LOW_SUN_AZIMUTH : SKYSH_HW_AZIMUTH;
    const double *sums = s->az_sums[low_sun], *half = s->az_half[low_sun];
    const double sin_ts = sin(ts);
    for (int r = 0; r < SKYSH_HW_RINGS; r++) {
        const double theta = s->theta[r], h0 = sin(0.5 * (theta - ts)), hav0 = h0 * h0, st = sin(theta) * sin_ts;
        double acc[3][3][SKYSH_HW_BANDS]; /* channel, term (exp, chi, cos^2), m */
        for (int c = 0; c < 3; c++) { for (int q = 0; q < 3; q++) { for (int m = 0; m < n; m++) { acc[c][q][m] = 0.0; } } }
        for (int j = 0; j < nj; j++) {
            const double hav = fmin(hav0 + st * half[j], 1.0), gamma = 2.0 * asin(sqrt(hav)), cg = 1.0 - 2.0 * hav;
            const double cg2 = cg * cg;
            for (int c = 0; c < 3; c++) {
                const double e = params[10 * c + 4], h = params[10 * c + 8];
                const double den = 1.0 + h * (h - 2.0 * cg), chi = (1.0 + cg2) / (den * sqrt(den)), ex = exp(e * gamma);
                for (int m = 0; m < n; m++) {
                    const double sm = sums[j * n + m];
                    acc[c][0][m] += ex * sm;
                    acc[c][1][m] += chi * sm;
                    acc[c][2][m] += cg2 * sm;
                }
            }
        }
        for (int c = 0; c < 3; c++) {
            const double *p = params + 10 * c;
            const double radial = (1.0 + p[0] * exp(p[1] / (s->cos_t[r] + SKYSH_HW_HORIZON_OFFSET))) * p[9] * s->weight[r];
            for (int m = 0; m < n; m++) {
                double by_m = p[3] * acc[c][0][m] + (p[6] * acc[c][1][m] + p[5] * acc[c][2][m]);
                if (m == 0) { by_m += 2.0 * SKYSH_HW_PI * (p[2] + p[7] * s->sqrt_cos[r]); }
                s->moments[(r * 3 + c) * n + m] = radial * by_m;
            }
        }
    }
    const double *cheb = SKYSH_HW_CHEBYSHEV + (n - 1) * (n - 1) * n * n / 4; /* sum_{k<n} k^3 = (n (n - 1) / 2)^2 */
    for (int i = 0; i < count; i++) { for (int c = 0; c < 3; c++) { s->sh[i][c] = 0.0; } }
    for (int r = 0; r < SKYSH_HW_RINGS; r++) {
        const double theta = s->theta[r], st = sin(theta);
        for (int i = 0; i < count; i++) { s->rows[i] = 0.0; }
        for (int k = 0; k < n; k++) {
            const double ck = cos(theta * (double)k);
            for (int i = 0; i < count; i++) { s->rows[i] += ck * cheb[k * count + i]; }
        }
        for (int i = 0; i < count; i++) {
            const int m = SKYSH_HW_M_OF[i];
            const double y = s->rows[i] * pow(st, (double)m), *mo = s->moments + r * 3 * n + m;
            for (int c = 0; c < 3; c++) { s->sh[i][c] += y * mo[c * n]; }
        }
    }
    const double alpha = fmod(phi_s, SKYSH_HW_TWO_PI); /* Habel eq. 4 for coefficients whose m < 0 vanish */
    for (int l = 0, i = 0; l < n; l++) {
        for (int m = -l; m <= l; m++, i++) {
            const double turn = alpha * (double)(m < 0 ? -m : m);
            const double factor = m < 0 ? sin(turn) : cos(turn);
            for (int c = 0; c < 3; c++) { s->sh[i][c] = s->sh[i][c] * factor * SKYSH_HW_EFFICACY; }
        }
    }
}

/* The sky's SH for one frame (see the header): sun zenith and azimuth in radians, turbidity, the ground albedo per
 * channel (or NULL), flags (SKYSH_HW_GIBBS | SKYSH_HW_DERING | SKYSH_HW_IRRADIANCE), out[3 bands^2]. */
static inline int skysh_hw_coefficients(skysh_hw_state *state, double sun_zenith, double turbidity, double sun_azimuth,
                                        const double *albedo, int flags, double *out)
{
    const int bands = state && state->magic == SKYSH_HW_MAGIC ? state->bands : 0;
    if (bands == 0) { return -7; } /* out's length is unknown: untouched */
    int rc = skysh_hw_check(sun_zenith, turbidity, sun_azimuth, albedo);
    if (rc == 0 && (flags & ~(SKYSH_HW_GIBBS | SKYSH_HW_DERING | SKYSH_HW_IRRADIANCE)) != 0) { rc = -6; }
    if (rc == 0 && (flags & SKYSH_HW_DERING) && bands != SKYSH_HW_BANDS) { rc = -5; }
    if (rc != 0) {
        for (int k = 0; k < 3 * bands * bands; k++) { out[k] = 0.0; }
        return rc;
    }
    skysh_hw_project(state, sun_zenith, turbidity, sun_azimuth, albedo);
    if (flags & SKYSH_HW_GIBBS) { /* Habel eq. 5: the zonal coefficients (l, 0) */
        const double *g = SKYSH_HW_GIBBS_FACTORS + bands * (bands - 1) / 2;
        for (int l = 0; l < bands; l++) { for (int c = 0; c < 3; c++) { state->sh[l * (l + 1)][c] *= g[l]; } }
    }
    if (flags & SKYSH_HW_DERING) {
        double scales[SKYSH_HW_BANDS], position[1];
        rc = skysh_hw_dering(state->sh, scales, position);
    }
    for (int l = 0; l < bands; l++) {
        const double a = (flags & SKYSH_HW_IRRADIANCE) ? SKYSH_HW_LOBE[l] : 1.0;
        for (int i = l * l; i < (l + 1) * (l + 1); i++) {
            for (int c = 0; c < 3; c++) { out[3 * i + c] = (flags & SKYSH_HW_IRRADIANCE) ? state->sh[i][c] * a : state->sh[i][c]; }
        }
    }
    return rc;
}

#endif /* SKYSH_HOSEK_WILKIE_H */
