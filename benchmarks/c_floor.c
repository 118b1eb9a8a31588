/*
 * The floor of the C export's per-frame kernel (benchmarks/bench_c_floor.py compiles and runs this file).
 *
 * The least hand-written C for the arithmetic skysh_coefficients does in each timed case, over the tables of
 * the same generated header (#include SKYSH_HEADER: its SKYSH_TABLE, SKYSH_IRRADIANCE, SKYSH_SUN_TABLE ...,
 * term-major as c_like_data.h documents them), so that the floor and the export read identical numbers:
 *
 *   - the Chebyshev terms T_i(x) T_j(y) by the recurrence;
 *   - the term-major dot product acc[o] += w[q] T[q OUT + o], one pass over the outputs a term;
 *   - the luminance scale (tan, cos, exp as the export), the Gibbs factor, the per-band factor;
 *   - the rotation about Z by one cos, one sin and the angle-addition recurrence;
 *   - lit: the sun's Chebyshev sum of ln XYZ, exp, XYZ -> RGB, the ground's zonal terms and the sun's
 *     windowed lobes (cos(k ts), sin(k ts) by the same recurrence).
 *
 * No domain checks, no options read at run time beyond the case: the floor knows its case.
 *
 * Built twice by the benchmark: with -DFLOOR_EXPORT_UNIT it is only bench_export(), the export's call in a
 * unit of its own (so that the export may come from another header, e.g. an older checkout's); without it,
 * the floor and main(), which times both in alternating rounds with the thread's CPU clock. Both calls cross
 * a unit boundary, so neither is inlined into the timing loop.
 *
 * main(case, calls, rounds) prints one JSON object: the median ns per call of each over the rounds and the
 * largest |export - floor| over |DC| (worst channel, worst frame). Cases: 0 radiance (Gibbs filter), 1
 * irradiance (no Gibbs filter, no deringing), 2 lit (radiance with the sun and a 0.2 grey ground), 3
 * irradiance by the defaults (deringing asked: 3 bands the certified table, which the floor evaluates; other
 * band counts the deringing, which it does not: floor figures 0).
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include SKYSH_HEADER

enum { CASE_RADIANCE, CASE_IRRADIANCE, CASE_LIT, CASE_DEFAULT_IRRADIANCE, CASES };

int bench_export(int kase, double ts, double t, double az, double out[SKYSH_COUNT][3]);

#ifdef FLOOR_EXPORT_UNIT
int bench_export(int kase, double ts, double t, double az, double out[SKYSH_COUNT][3])
{
    static const skysh_real grey[3] = {0.2, 0.2, 0.2};
    switch (kase) {
    case CASE_RADIANCE:
        return skysh_coefficients(ts, t, az, 1, 0, 0, 0, NULL, SKYSH_BY_INTENT, out);
    case CASE_IRRADIANCE:
        return skysh_coefficients(ts, t, az, 0, 0, 1, 0, NULL, SKYSH_BY_INTENT, out);
    case CASE_LIT:
        return skysh_coefficients(ts, t, az, 1, 0, 0, 1, grey, SKYSH_BY_INTENT, out);
    default:
        return skysh_coefficients(ts, t, az, 0, SKYSH_DERING, 1, 0, NULL, SKYSH_BY_INTENT, out);
    }
}
#else
#define FLOOR_ALBEDO 0.2 /* the lit case's grey ground */

/* w[i (DY + 1) + j] = T_i(x) T_j(y) of the sky's variables. */
static void floor_weights(double ts, double t, double w[SKYSH_TERMS])
{
    double tx[SKYSH_DX + 1], ty[SKYSH_DY + 1];
    double x = fmin(1.0, fmax(-1.0, ts * SKYSH_X_SCALE - SKYSH_X_SHIFT));
    double y = fmin(1.0, fmax(-1.0, log(t) * SKYSH_Y_SCALE - SKYSH_Y_SHIFT));
    tx[0] = ty[0] = 1.0;
    tx[1] = x;
    ty[1] = y;
    for (int i = 2; i <= SKYSH_DX; ++i)
        tx[i] = 2.0 * x * tx[i - 1] - tx[i - 2];
    for (int j = 2; j <= SKYSH_DY; ++j)
        ty[j] = 2.0 * y * ty[j - 1] - ty[j - 2];
    for (int i = 0; i <= SKYSH_DX; ++i)
        for (int j = 0; j <= SKYSH_DY; ++j)
            w[i * (SKYSH_DY + 1) + j] = tx[i] * ty[j];
}

/* acc[o] = sum_q w[q] T[q outputs + o], eight terms a pass over the outputs (T: SKYSH_TABLE or SKYSH_IRRADIANCE). */
#define FLOOR_ROWS(name, T, OUTPUTS)                                                                             \
    static void name(const double w[SKYSH_TERMS], double acc[SKYSH_OUTPUTS])                                   \
    {                                                                                                           \
        for (int o = 0; o < OUTPUTS; ++o)                                                                       \
            acc[o] = 0.0;                                                                                       \
        for (int q = 0; q < SKYSH_TERMS - SKYSH_TERMS % 8; q += 8) {                                            \
            const double *t = T + q * (OUTPUTS), *x = w + q;                                                    \
            for (int o = 0; o < OUTPUTS; ++o)                                                                   \
                acc[o] += x[0] * t[o] + x[1] * t[(OUTPUTS) + o] + x[2] * t[2 * (OUTPUTS) + o]                   \
                    + x[3] * t[3 * (OUTPUTS) + o] + x[4] * t[4 * (OUTPUTS) + o] + x[5] * t[5 * (OUTPUTS) + o]   \
                    + x[6] * t[6 * (OUTPUTS) + o] + x[7] * t[7 * (OUTPUTS) + o];                                \
        }                                                                                                       \
        for (int q = SKYSH_TERMS - SKYSH_TERMS % 8; q < SKYSH_TERMS; ++q)                                       \
            for (int o = 0; o < OUTPUTS; ++o)                                                                   \
                acc[o] += w[q] * T[q * (OUTPUTS) + o];                                                          \
    }
FLOOR_ROWS(floor_sky_rows, SKYSH_TABLE, SKYSH_OUTPUTS)
#if SKYSH_IRRADIANCE_TABLE
FLOOR_ROWS(floor_table_rows, SKYSH_IRRADIANCE, 3 * SKYSH_HALF)
#endif

/* c[k] = cos(k a), s[k] = sin(k a) from cos a, sin a by the angle addition. */
static void floor_turns(double ca, double sa, double c[SKYSH_BANDS], double s[SKYSH_BANDS])
{
    c[0] = 1.0;
    s[0] = 0.0;
    for (int k = 1; k < SKYSH_BANDS; ++k) {
        c[k] = c[k - 1] * ca - s[k - 1] * sa;
        s[k] = s[k - 1] * ca + c[k - 1] * sa;
    }
}

/* Y_z / F_Y(0, ts) (Preetham 1999). */
static double floor_luminance_scale(double ts, double ct, double t)
{
    const double *p = SKYSH_PEREZ_Y;
    double chi = (SKYSH_ZENITH_CHI - t / 120.0) * (SKYSH_PI - 2.0 * ts);
    double yz = 1000.0 * ((SKYSH_ZENITH_A * t - SKYSH_ZENITH_B) * tan(chi) - SKYSH_ZENITH_C * t + SKYSH_ZENITH_D);
    double f = (1.0 + (p[0] * t + p[1]) * exp(p[2] * t + p[3]))
        * (1.0 + (p[4] * t + p[5]) * exp((p[6] * t + p[7]) * ts) + (p[8] * t + p[9]) * ct * ct);
    return yz / f;
}

/* The sun (its RGB, clamped, times its windowed lobes) and the grey ground added to out (radiance, Gibbs on). */
static void floor_lights(double ts, double ct, double t, const double c[SKYSH_BANDS], const double s[SKYSH_BANDS],
                         const double e_sky[3], double out[SKYSH_COUNT][3])
{
    double sx[SKYSH_SUN_DX + 1], sy[SKYSH_SUN_DY + 1], ln[3] = {0.0, 0.0, 0.0}, rgb[3], tc[SKYSH_BANDS], tsn[SKYSH_BANDS];
    double m = 1.0 / (ct + SKYSH_KASTEN_A * pow(SKYSH_KASTEN_B - ts * SKYSH_DEG, SKYSH_KASTEN_NEG_C));
    double x = fmin(1.0, fmax(-1.0, (m - SKYSH_SUN_M0) * SKYSH_SUN_X_SCALE - 1.0));
    double y = fmin(1.0, fmax(-1.0, (t - SKYSH_SUN_TMIN) * SKYSH_SUN_Y_SCALE - 1.0));
    sx[0] = sy[0] = 1.0;
    sx[1] = x;
    sy[1] = y;
    for (int i = 2; i <= SKYSH_SUN_DX; ++i)
        sx[i] = 2.0 * x * sx[i - 1] - sx[i - 2];
    for (int j = 2; j <= SKYSH_SUN_DY; ++j)
        sy[j] = 2.0 * y * sy[j - 1] - sy[j - 2];
    for (int i = 0; i <= SKYSH_SUN_DX; ++i)
        for (int j = 0; j <= SKYSH_SUN_DY; ++j) {
            const double *row = SKYSH_SUN_TABLE + 3 * (i * (SKYSH_SUN_DY + 1) + j);
            double wij = sx[i] * sy[j];
            ln[0] += wij * row[0];
            ln[1] += wij * row[1];
            ln[2] += wij * row[2];
        }
    ln[0] = exp(ln[0]);
    ln[1] = exp(ln[1]);
    ln[2] = exp(ln[2]);
    for (int ch = 0; ch < 3; ++ch)
        rgb[ch] = SKYSH_SUN_RGB[3 * ch] * ln[0] + SKYSH_SUN_RGB[3 * ch + 1] * ln[1] + SKYSH_SUN_RGB[3 * ch + 2] * ln[2];
    for (int l = 0; l < SKYSH_BANDS; ++l) {
        double g = SKYSH_GROUND[l] * SKYSH_GIBBS[l] * SKYSH_INV_PI * FLOOR_ALBEDO;
        for (int ch = 0; ch < 3; ++ch)
            out[l * (l + 1)][ch] += g * (e_sky[ch] + ct * rgb[ch]);
    }
    for (int ch = 0; ch < 3; ++ch)
        rgb[ch] = fmax(rgb[ch], SKYSH_SUN_CLAMP);
    floor_turns(ct, sin(ts), tc, tsn);
    for (int l = 0; l < SKYSH_BANDS; ++l)
        for (int k = 0; k <= l; ++k) {
            const double *trig = SKYSH_SUN_TRIG + 2 * SKYSH_BANDS * (l * (l + 1) / 2 + k);
            double lobe = 0.0;
            for (int q = 0; q < SKYSH_BANDS; ++q)
                lobe += trig[q] * tc[q];
            for (int q = 0; q < SKYSH_BANDS; ++q)
                lobe += trig[SKYSH_BANDS + q] * tsn[q];
            for (int ch = 0; ch < 3; ++ch) {
                out[l * (l + 1) + k][ch] += lobe * c[k] * rgb[ch];
                if (k > 0)
                    out[l * (l + 1) - k][ch] += lobe * s[k] * rgb[ch];
            }
        }
}

/* The floor of case kase (no checks: the frame is inside the domain). */
static int floor_call(int kase, double ts, double t, double az, double out[SKYSH_COUNT][3])
{
    double w[SKYSH_TERMS], acc[SKYSH_OUTPUTS], c[SKYSH_BANDS], s[SKYSH_BANDS], e_sky[3];
    int gibbs = kase == CASE_RADIANCE || kase == CASE_LIT, lobe = !gibbs;
    floor_weights(ts, t, w);
#if SKYSH_IRRADIANCE_TABLE
    if (kase == CASE_DEFAULT_IRRADIANCE)
        floor_table_rows(w, acc);
    else
#endif
        floor_sky_rows(w, acc);
    double ct = cos(ts), scale = floor_luminance_scale(ts, ct, t), phi = fmod(az, SKYSH_TWO_PI);
    floor_turns(cos(phi), sin(phi), c, s);
    for (int l = 0; l < SKYSH_BANDS; ++l) {
        double f = lobe ? SKYSH_LOBE[l] * scale : scale, g = gibbs ? SKYSH_GIBBS[l] : 1.0;
        int row = 3 * (l * (l + 1) / 2), n = l * (l + 1);
        for (int ch = 0; ch < 3; ++ch)
            out[n][ch] = acc[row + ch] * g * f;
        for (int k = 1; k <= l; ++k)
            for (int ch = 0; ch < 3; ++ch) {
                double v = acc[row + 3 * k + ch] * f;
                out[n + k][ch] = v * c[k];
                out[n - k][ch] = v * s[k];
            }
    }
    if (kase == CASE_LIT) {
        for (int ch = 0; ch < 3; ++ch)
            e_sky[ch] = SKYSH_HF * acc[3 + ch] * scale;
        floor_lights(ts, ct, t, c, s, e_sky, out);
    }
    return 0;
}

typedef int (*call_fn)(int, double, double, double, double[SKYSH_COUNT][3]);

static double thread_seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

#define FRAMES 256 /* distinct frames a round cycles through */

int main(int argc, char **argv)
{
    static double frames[FRAMES][3], export_ns[1000], floor_ns[1000];
    double out[SKYSH_COUNT][3], ref[SKYSH_COUNT][3], worst = 0.0, sink = 0.0;
    unsigned long seed = 12345;
    int kase = argc > 1 ? atoi(argv[1]) : 0, calls = argc > 2 ? atoi(argv[2]) : 2000;
    int rounds = argc > 3 ? atoi(argv[3]) : 21, floored;
    if (kase < 0 || kase >= CASES || calls < 1 || rounds < 1 || rounds > 1000)
        return 2;
    floored = kase != CASE_DEFAULT_IRRADIANCE || SKYSH_IRRADIANCE_TABLE;
    for (int i = 0; i < FRAMES; ++i) /* sun zenith [0, pi/2], turbidity [2.5, 6], azimuth [-pi, pi) */
        for (int k = 0; k < 3; ++k) {
            seed = seed * 6364136223846793005UL + 1442695040888963407UL;
            double u = (double)(seed >> 11) / 9007199254740992.0;
            frames[i][k] = k == 0 ? u * SKYSH_PI / 2.0 : (k == 1 ? 2.5 + 3.5 * u : SKYSH_PI * (2.0 * u - 1.0));
        }
    for (int i = 0; floored && i < FRAMES; ++i) { /* the floor reproduces the export */
        if (bench_export(kase, frames[i][0], frames[i][1], frames[i][2], ref) != 0)
            return 3;
        floor_call(kase, frames[i][0], frames[i][1], frames[i][2], out);
        for (int ch = 0; ch < 3; ++ch)
            for (int n = 0; n < SKYSH_COUNT; ++n)
                worst = fmax(worst, fabs(out[n][ch] - ref[n][ch]) / fabs(ref[0][ch]));
    }
    for (int r = -1; r < rounds; ++r) /* round -1 warms up; the order alternates round by round */
        for (int half = 0; half < 2; ++half) {
            int is_export = (half + r) % 2 == 0;
            call_fn fn = is_export ? bench_export : floor_call;
            if (!is_export && !floored)
                continue;
            double start = thread_seconds();
            for (int i = 0; i < calls; ++i) {
                const double *f = frames[i % FRAMES];
                fn(kase, f[0], f[1], f[2], out);
                sink += out[SKYSH_COUNT - 1][i % 3];
            }
            double ns = 1e9 * (thread_seconds() - start) / calls;
            if (r >= 0)
                (is_export ? export_ns : floor_ns)[r] = ns;
        }
    qsort(export_ns, (size_t)rounds, sizeof(double), by_value);
    qsort(floor_ns, (size_t)rounds, sizeof(double), by_value);
    printf("{\"export_ns\": %.1f, \"floor_ns\": %.1f, \"max_diff_over_dc\": %.3g, \"checksum\": %.6g}\n",
           export_ns[rounds / 2], floored ? floor_ns[rounds / 2] : 0.0, worst, sink);
    return 0;
}
#endif
