/*
 * The sky's SH coefficients in C, GLSL and HLSL: one kernel (skysh/export/templates/c_like_kernel.h)
 * over the words of c_like_words_c.h, c_like_words_glsl.glsl or c_like_words_hlsl.hlsl (then
 * c_like_words_shader.glsl), c_like_words_math.h and the numbers of the data section (c_like_data.h,
 * c_like_engine.h), the steps of skysh.SkySH.coefficients in its order (skysh.export.c_like lists them):
 *
 *  1. refuse a frame outside the domain (C: -1 .. -5, the shaders: false; the output zeroed);
 *  2. x and y of the sun zenith and the log turbidity, their Chebyshev polynomials;
 *  3. each stored (m >= 0) coefficient as a sum over the terms T_i(x) T_j(y) of SKYSH_TABLE (Habel
 *     eq. 1), or of the certified irradiance table SKYSH_IRRADIANCE: the tables are term-major, one pass
 *     over every output of a term at a time (skysh_rows), which compilers vectorise;
 *  4. the Gibbs filter and the luminance scale Y_z / F_Y(0, ts) (Preetham 1999);
 *  5. the rotation about Z by the sun's azimuth (Habel eq. 4): cos(m phi) and sin(m phi) from one cos
 *     and one sin of phi by the angle addition (skysh_turns), shared with the sun;
 *  6. the deringing (c_like_dering3.h; C at 5..7 bands: c_like_dering_certificate_c.h);
 *  7. the sun and the ground;
 *  8. the per-band factor (the clamped cosine A_l, or an engine's folded factor);
 *  9. with an engine, the rest of its linear map as (output, input, factor) terms and offsets.
 *
 * In C every function is static inline; skysh_real is 64-bit, or float with SKYSH_FLOAT. In the
 * shaders everything is float32; the flags are bool and a function returns true where C returns 0.
 * The public functions, skysh_coefficients, skysh_sun_light and (with an engine)
 * skysh_engine_coefficients, call these in each language's own words: c_like_api_c.h,
 * c_like_api_shader.glsl.
 */

#define SKYSH_OUTPUTS (3 * SKYSH_ROWS) /* the outputs of one term of SKYSH_TABLE: channel c of stored row r is 3 r + c */

/* Y_z / F_Y(0, ts): the sky's luminance scale, cd/m^2 (Preetham 1999, appendix); ct = cos(ts), the caller's. */
SKYSH_FN SKYSH_REAL skysh_luminance_scale(SKYSH_REAL ts, SKYSH_REAL ct, SKYSH_REAL t)
{
    SKYSH_REAL chi = (SKYSH_ZENITH_CHI - t / 120.0f) * (SKYSH_PI - 2.0f * ts);
    SKYSH_REAL yz = 1000.0f * ((SKYSH_ZENITH_A * t - SKYSH_ZENITH_B) * SKYSH_TAN(chi) - SKYSH_ZENITH_C * t + SKYSH_ZENITH_D);
    SKYSH_REAL f = (1.0f + (SKYSH_PEREZ_Y[0] * t + SKYSH_PEREZ_Y[1]) * SKYSH_EXP(SKYSH_PEREZ_Y[2] * t + SKYSH_PEREZ_Y[3]))
        * (1.0f + (SKYSH_PEREZ_Y[4] * t + SKYSH_PEREZ_Y[5]) * SKYSH_EXP((SKYSH_PEREZ_Y[6] * t + SKYSH_PEREZ_Y[7]) * ts)
           + (SKYSH_PEREZ_Y[8] * t + SKYSH_PEREZ_Y[9]) * ct * ct);
    return yz / f;
}

/*
 * The irradiance_table argument (skysh.SkySH.coefficients' irradiance_table): 1 when the sky's rows come from the
 * certified irradiance table (docs/irradiance.md), 0 when not, -1 when refused. SKYSH_BY_INTENT: the table for
 * diffuse light (mode 1 irradiance, 2 an engine) without the Gibbs filter and with deringing, where this export
 * has it (SKYSH_IRRADIANCE_TABLE); 0: never (the sky's rows, filtered and deringed as asked); 1: always
 * (refused with gibbs or without the table).
 */
SKYSH_FN int skysh_use_table(int choice, int mode, SKYSH_BOOL gibbs, SKYSH_BOOL dering)
{
    if (choice == SKYSH_BY_INTENT)
        return (SKYSH_IRRADIANCE_TABLE != 0 && mode != 0 && !gibbs && dering) ? 1 : 0;
    if (choice == 0)
        return 0;
    return (choice == 1 && SKYSH_IRRADIANCE_TABLE != 0 && !gibbs) ? 1 : -1;
}

/* Step 8's factor of band l: mode 0 none (radiance), 1 the clamped cosine A_l (irradiance), 2 the engine's. */
SKYSH_FN SKYSH_REAL skysh_band_factor(int mode, int l)
{
#ifdef SKYSH_ENGINE_COUNT
    if (mode == 2)
        return SKYSH_ENGINE_BAND[l];
#endif
    return mode == 1 ? SKYSH_LOBE[l] : 1.0f;
}

/*
 * cos(k a) and sin(k a), k = 0 .. SKYSH_BANDS - 1, from ca = cos(a) and sa = sin(a) by the angle addition
 * cos((k + 1) a) = cos(k a) ca - sin(k a) sa, sin((k + 1) a) = sin(k a) ca + cos(k a) sa: one cos and one sin
 * for every k (about an ulp more error a step; tests/export/test_export_kernel.py bounds it against libm).
 */
SKYSH_FN void skysh_turns(SKYSH_REAL ca, SKYSH_REAL sa, SKYSH_OUT SKYSH_REAL c[SKYSH_BANDS], SKYSH_OUT SKYSH_REAL s[SKYSH_BANDS])
{
    c[0] = 1.0f;
    s[0] = 0.0f;
    for (int k = 1; k < SKYSH_BANDS; ++k) {
        c[k] = c[k - 1] * ca - s[k - 1] * sa;
        s[k] = s[k - 1] * ca + c[k - 1] * sa;
    }
}

/*
 * Habel eq. (1) for every stored coefficient at once: acc[o] = sum_q w[q] SKYSH_TABLE[q SKYSH_OUTPUTS + o], output
 * o = 3 r + c. The table is term-major, so each pass over the outputs (a loop compilers vectorise) adds eight
 * terms, reading and writing the sums once for eight (benchmarks/bench_c_floor.py).
 */
SKYSH_FN void skysh_rows(SKYSH_IN SKYSH_REAL w[SKYSH_TERMS], SKYSH_OUT SKYSH_REAL acc[SKYSH_OUTPUTS])
{
    for (int o = 0; o < SKYSH_OUTPUTS; ++o)
        acc[o] = 0.0f;
    for (int q = 0; q < SKYSH_TERMS - SKYSH_TERMS % 8; q += 8)
        for (int o = 0; o < SKYSH_OUTPUTS; ++o) {
            int k = q * SKYSH_OUTPUTS + o;
            acc[o] += w[q] * SKYSH_TABLE[k] + w[q + 1] * SKYSH_TABLE[k + SKYSH_OUTPUTS] + w[q + 2] * SKYSH_TABLE[k + 2 * SKYSH_OUTPUTS]
                + w[q + 3] * SKYSH_TABLE[k + 3 * SKYSH_OUTPUTS] + w[q + 4] * SKYSH_TABLE[k + 4 * SKYSH_OUTPUTS]
                + w[q + 5] * SKYSH_TABLE[k + 5 * SKYSH_OUTPUTS] + w[q + 6] * SKYSH_TABLE[k + 6 * SKYSH_OUTPUTS]
                + w[q + 7] * SKYSH_TABLE[k + 7 * SKYSH_OUTPUTS];
        }
    for (int q = SKYSH_TERMS - SKYSH_TERMS % 8; q < SKYSH_TERMS; ++q) /* the last terms, if any */
        for (int o = 0; o < SKYSH_OUTPUTS; ++o)
            acc[o] += w[q] * SKYSH_TABLE[q * SKYSH_OUTPUTS + o];
}

/*
 * The unfiltered sky's c_10 alone (stored row 1 of SKYSH_TABLE, the ground's E_h) into acc[3 .. 5] where the rows
 * come from the certified table; zeros without a ground, which alone reads it.
 */
SKYSH_FN void skysh_c10(SKYSH_BOOL ground, SKYSH_IN SKYSH_REAL w[SKYSH_TERMS], SKYSH_INOUT SKYSH_REAL acc[SKYSH_OUTPUTS])
{
    for (int c = 0; c < 3; ++c)
        acc[3 + c] = 0.0f;
    if (ground)
        for (int q = 0; q < SKYSH_TERMS; ++q)
            for (int c = 0; c < 3; ++c)
                acc[3 + c] += w[q] * SKYSH_TABLE[q * SKYSH_OUTPUTS + 3 + c];
}

#if SKYSH_IRRADIANCE_TABLE
/* skysh_rows over the certified irradiance table (3 bands, where its SKYSH_HALF rows are all SKYSH_ROWS). */
SKYSH_FN void skysh_table_rows(SKYSH_IN SKYSH_REAL w[SKYSH_TERMS], SKYSH_OUT SKYSH_REAL acc[SKYSH_OUTPUTS])
{
    for (int o = 0; o < SKYSH_OUTPUTS; ++o)
        acc[o] = 0.0f;
    for (int q = 0; q < SKYSH_TERMS - SKYSH_TERMS % 8; q += 8)
        for (int o = 0; o < SKYSH_OUTPUTS; ++o) {
            int k = q * SKYSH_OUTPUTS + o;
            acc[o] += w[q] * SKYSH_IRRADIANCE[k] + w[q + 1] * SKYSH_IRRADIANCE[k + SKYSH_OUTPUTS] + w[q + 2] * SKYSH_IRRADIANCE[k + 2 * SKYSH_OUTPUTS]
                + w[q + 3] * SKYSH_IRRADIANCE[k + 3 * SKYSH_OUTPUTS] + w[q + 4] * SKYSH_IRRADIANCE[k + 4 * SKYSH_OUTPUTS]
                + w[q + 5] * SKYSH_IRRADIANCE[k + 5 * SKYSH_OUTPUTS] + w[q + 6] * SKYSH_IRRADIANCE[k + 6 * SKYSH_OUTPUTS]
                + w[q + 7] * SKYSH_IRRADIANCE[k + 7 * SKYSH_OUTPUTS];
        }
    for (int q = SKYSH_TERMS - SKYSH_TERMS % 8; q < SKYSH_TERMS; ++q) /* the last terms, if any */
        for (int o = 0; o < SKYSH_OUTPUTS; ++o)
            acc[o] += w[q] * SKYSH_IRRADIANCE[q * SKYSH_OUTPUTS + o];
}
#endif

/* The sun's RGB direct normal illuminance (lux; Preetham 1999 appendix, fitted: skysh.lighting.sunlight); ct = cos(ts). */
SKYSH_FN void skysh_sun_rgb(SKYSH_REAL ts, SKYSH_REAL ct, SKYSH_REAL t, SKYSH_OUT SKYSH_RGB(rgb))
{
    SKYSH_REAL sx[SKYSH_SUN_DX + 1];
    SKYSH_REAL sy[SKYSH_SUN_DY + 1];
    SKYSH_REAL ln[3];
    SKYSH_REAL m = 1.0f / (ct + SKYSH_KASTEN_A * SKYSH_POW(SKYSH_KASTEN_B - ts * SKYSH_DEG, SKYSH_KASTEN_NEG_C));
    SKYSH_REAL x = (m - SKYSH_SUN_M0) * SKYSH_SUN_X_SCALE - 1.0f; /* m: Kasten's (1966) air mass */
    SKYSH_REAL y = (t - SKYSH_SUN_TMIN) * SKYSH_SUN_Y_SCALE - 1.0f;
    x = x < -1.0f ? -1.0f : (x > 1.0f ? 1.0f : x);
    y = y < -1.0f ? -1.0f : (y > 1.0f ? 1.0f : y);
    sx[0] = 1.0f;
    sy[0] = 1.0f;
    for (int i = 1; i <= SKYSH_SUN_DX; ++i)
        sx[i] = i == 1 ? x : 2.0f * x * sx[i - 1] - sx[i - 2];
    for (int j = 1; j <= SKYSH_SUN_DY; ++j)
        sy[j] = j == 1 ? y : 2.0f * y * sy[j - 1] - sy[j - 2];
    SKYSH_REAL lx = 0.0f; /* three sums in registers, not one array in memory (its latency, without -O3) */
    SKYSH_REAL ly = 0.0f;
    SKYSH_REAL lz = 0.0f;
    for (int i = 0; i <= SKYSH_SUN_DX; ++i)
        for (int j = 0; j <= SKYSH_SUN_DY; ++j) {
            SKYSH_REAL w = sx[i] * sy[j];
            int base = 3 * (i * (SKYSH_SUN_DY + 1) + j);
            lx += w * SKYSH_SUN_TABLE[base];
            ly += w * SKYSH_SUN_TABLE[base + 1];
            lz += w * SKYSH_SUN_TABLE[base + 2];
        }
    ln[0] = SKYSH_EXP(lx);
    ln[1] = SKYSH_EXP(ly);
    ln[2] = SKYSH_EXP(lz);
    for (int c = 0; c < 3; ++c)
        rgb[c] = SKYSH_SUN_RGB[3 * c] * ln[0] + SKYSH_SUN_RGB[3 * c + 1] * ln[1] + SKYSH_SUN_RGB[3 * c + 2] * ln[2];
}

/*
 * The ground (albedo x (E_sky + cos(ts) E_sun) / pi, zonal, Gibbs-filtered with gibbs) and the
 * sun (a delta windowed by skysh.model.solar.sun_window, colour clamped at SKYSH_SUN_CLAMP) added to
 * the rotated radiance coeffs; e_sky = sqrt(4 pi / 3) c_10 of the unfiltered sky (lux); ct = cos(ts);
 * rc[k], rs[k]: cos(k phi), sin(k phi) (skysh_turns).
 */
SKYSH_FN void skysh_add_lights(SKYSH_REAL ts, SKYSH_REAL ct, SKYSH_REAL t, SKYSH_IN SKYSH_REAL rc[SKYSH_BANDS],
                               SKYSH_IN SKYSH_REAL rs[SKYSH_BANDS], SKYSH_BOOL sun, SKYSH_BOOL ground, SKYSH_BOOL gibbs,
                               SKYSH_IN SKYSH_RGB(albedo), SKYSH_IN SKYSH_RGB(e_sky),
                               SKYSH_INOUT SKYSH_RGB(coeffs[SKYSH_COUNT]))
{
    SKYSH_RGB(rgb);
    for (int c = 0; c < 3; ++c)
        rgb[c] = 0.0f;
    if (sun)
        skysh_sun_rgb(ts, ct, t, rgb);
    if (ground)
        for (int l = 0; l < SKYSH_BANDS; ++l) {
            SKYSH_REAL g = SKYSH_GROUND[l] * (gibbs ? SKYSH_GIBBS[l] : 1.0f) * SKYSH_INV_PI;
            for (int c = 0; c < 3; ++c)
                coeffs[l * (l + 1)][c] += g * albedo[c] * (e_sky[c] + ct * rgb[c]);
        }
    if (sun) {
        SKYSH_REAL tc[SKYSH_BANDS]; /* cos(q ts), sin(q ts): the columns of SKYSH_SUN_TRIG */
        SKYSH_REAL tsn[SKYSH_BANDS];
        skysh_turns(ct, SKYSH_SIN(ts), tc, tsn);
        for (int c = 0; c < 3; ++c)
            rgb[c] = rgb[c] > SKYSH_SUN_CLAMP ? rgb[c] : SKYSH_SUN_CLAMP;
        for (int l = 0; l < SKYSH_BANDS; ++l)
            for (int k = 0; k <= l; ++k) { /* stored r, then its m = k and m = -k */
                int r = l * (l + 1) / 2 + k;
                SKYSH_REAL y = 0.0f;
                for (int q = 0; q < SKYSH_BANDS; ++q)
                    y += SKYSH_SUN_TRIG[2 * SKYSH_BANDS * r + q] * tc[q];
                for (int q = 0; q < SKYSH_BANDS; ++q)
                    y += SKYSH_SUN_TRIG[(2 * r + 1) * SKYSH_BANDS + q] * tsn[q];
                for (int c = 0; c < 3; ++c)
                    coeffs[l * (l + 1) + k][c] += y * rc[k] * rgb[c];
                if (k > 0)
                    for (int c = 0; c < 3; ++c)
                        coeffs[l * (l + 1) - k][c] += y * rs[k] * rgb[c];
            }
    }
}

/*
 * The steps of skysh_coefficients (mode: skysh_band_factor's) into coeffs[SKYSH_COUNT], RGB each.
 * C: ground_albedo NULL is a black ground; returns 0, or (coeffs zeroed) the codes of skysh_coefficients:
 * -1 for a parameter outside the domain, NaN or inf, -2 for dering without SKYSH_DERING, -3 for a
 * ground albedo outside [0, 1], -4 for the sun or the ground without its table (SKYSH_LIGHTS), -5 for
 * an irradiance_table refused. The shaders: true, or false for the same refusals.
 */
SKYSH_FN SKYSH_STATUS skysh_evaluate(SKYSH_REAL sun_zenith, SKYSH_REAL turbidity, SKYSH_REAL sun_azimuth,
                                     SKYSH_BOOL gibbs, SKYSH_BOOL dering, SKYSH_BOOL sun, SKYSH_ALBEDO ground_albedo,
                                     int irradiance_table, int mode, SKYSH_OUT SKYSH_RGB(coeffs[SKYSH_COUNT]))
{
    SKYSH_REAL tx[SKYSH_DX + 1];
    SKYSH_REAL ty[SKYSH_DY + 1];
    SKYSH_REAL w[SKYSH_TERMS];
    SKYSH_REAL acc[SKYSH_OUTPUTS];
    SKYSH_REAL rc[SKYSH_BANDS]; /* cos(k phi), sin(k phi) */
    SKYSH_REAL rs[SKYSH_BANDS];
    SKYSH_RGB(e_sky);
    SKYSH_RGB(albedo);
    for (int n = 0; n < SKYSH_COUNT; ++n)
        for (int c = 0; c < 3; ++c)
            coeffs[n][c] = 0.0f;
    for (int c = 0; c < 3; ++c)
        albedo[c] = SKYSH_ALBEDO_AT(ground_albedo, c);
    if (!(sun_zenith >= SKYSH_ZMIN && sun_zenith <= SKYSH_ZMAX) || !(turbidity >= SKYSH_TMIN && turbidity <= SKYSH_TMAX)
        || !(sun_azimuth - sun_azimuth == 0.0f))
        return SKYSH_FAIL(-1);
    if (dering && SKYSH_DERING == 0)
        return SKYSH_FAIL(-2);
    for (int c = 0; c < 3; ++c)
        if (!(albedo[c] >= 0.0f && albedo[c] <= 1.0f))
            return SKYSH_FAIL(-3);
    SKYSH_BOOL ground = albedo[0] != 0.0f || albedo[1] != 0.0f || albedo[2] != 0.0f;
    if ((sun && SKYSH_LIGHTS % 2 == 0) || (ground && SKYSH_LIGHTS / 2 == 0))
        return SKYSH_FAIL(-4);
    int table = skysh_use_table(irradiance_table, mode, gibbs, dering);
    if (table < 0)
        return SKYSH_FAIL(-5);
    SKYSH_BOOL deringed = dering && table == 0; /* the table is certified non-negative: never deringed */
    SKYSH_BOOL post = deringed || sun || ground; /* then step 8 follows steps 6 and 7 */
    SKYSH_REAL phi = SKYSH_FMOD(sun_azimuth, SKYSH_TWO_PI); /* as the runtime: exact */
    SKYSH_REAL x = sun_zenith * SKYSH_X_SCALE - SKYSH_X_SHIFT;
    SKYSH_REAL y = SKYSH_LOG(turbidity) * SKYSH_Y_SCALE - SKYSH_Y_SHIFT;
    x = x < -1.0f ? -1.0f : (x > 1.0f ? 1.0f : x);
    y = y < -1.0f ? -1.0f : (y > 1.0f ? 1.0f : y);
    tx[0] = 1.0f;
    ty[0] = 1.0f;
    for (int i = 1; i <= SKYSH_DX; ++i)
        tx[i] = i == 1 ? x : 2.0f * x * tx[i - 1] - tx[i - 2];
    for (int j = 1; j <= SKYSH_DY; ++j)
        ty[j] = j == 1 ? y : 2.0f * y * ty[j - 1] - ty[j - 2];
    for (int i = 0; i <= SKYSH_DX; ++i)
        for (int j = 0; j <= SKYSH_DY; ++j)
            w[i * (SKYSH_DY + 1) + j] = tx[i] * ty[j];
    if (table == 0) /* step 3 (with the table: the sky's c_10 only, for the ground) */
        skysh_rows(w, acc);
    else
        skysh_c10(ground, w, acc);
    SKYSH_REAL ct = SKYSH_COS(sun_zenith);
    SKYSH_REAL scale = skysh_luminance_scale(sun_zenith, ct, turbidity);
    for (int c = 0; c < 3; ++c)
        e_sky[c] = SKYSH_HF * acc[3 + c] * scale; /* E_h of the unfiltered sky (skysh.model.ground) */
#if SKYSH_IRRADIANCE_TABLE
    if (table == 1) /* step 3 from the certified irradiance table: never filtered, never deringed */
        skysh_table_rows(w, acc);
#endif
    skysh_turns(SKYSH_COS(phi), SKYSH_SIN(phi), rc, rs);
    for (int l = 0; l < SKYSH_BANDS; ++l) {
        SKYSH_REAL band = (post ? 1.0f : skysh_band_factor(mode, l)) * scale;
        int row = l * (l + 1) / 2; /* stored (l, 0) */
        if (gibbs)
            for (int c = 0; c < 3; ++c)
                acc[3 * row + c] *= SKYSH_GIBBS[l];
        for (int m = -l; m <= l; ++m) {
            int k = m < 0 ? -m : m;
            SKYSH_REAL rot = m < 0 ? rs[k] : rc[k];
            for (int c = 0; c < 3; ++c)
                coeffs[l * (l + 1) + m][c] = acc[3 * (row + k) + c] * rot * band;
        }
    }
#if SKYSH_DERING
    if (deringed) { /* step 6: SKYSH_DERING_NAME windows d in place, returns the window (unused here) */
        SKYSH_DERING_COEFFS(d);
        SKYSH_DREAL window[SKYSH_BANDS];
        SKYSH_DREAL position[1];
        for (int n = 0; n < SKYSH_COUNT; ++n)
            for (int c = 0; c < 3; ++c)
                SKYSH_DC(d, n, c) = coeffs[n][c];
        SKYSH_DERING_NAME(d, window, position);
        for (int n = 0; n < SKYSH_COUNT; ++n)
            for (int c = 0; c < 3; ++c)
                coeffs[n][c] = SKYSH_TO_REAL(SKYSH_DC(d, n, c));
    }
#endif
    if (sun || ground)
        skysh_add_lights(sun_zenith, ct, turbidity, rc, rs, sun, ground, gibbs, albedo, e_sky, coeffs);
    if (post && mode != 0)
        for (int l = 0; l < SKYSH_BANDS; ++l)
            for (int n = l * l; n < (l + 1) * (l + 1); ++n)
                for (int c = 0; c < 3; ++c)
                    coeffs[n][c] *= skysh_band_factor(mode, l);
    return SKYSH_OK;
}

/*
 * skysh_sun_light's steps (the public function: c_like_api_c.h, c_like_api_shader.glsl):
 * the unit vector towards the sun (Z up) and its RGB direct normal illuminance, lux, unclamped.
 */
SKYSH_FN SKYSH_STATUS skysh_evaluate_sun_light(SKYSH_REAL sun_zenith, SKYSH_REAL turbidity, SKYSH_REAL sun_azimuth,
                                               SKYSH_OUT SKYSH_RGB(direction), SKYSH_OUT SKYSH_RGB(rgb))
{
    for (int c = 0; c < 3; ++c) {
        direction[c] = 0.0f;
        rgb[c] = 0.0f;
    }
    if (!(sun_zenith >= SKYSH_ZMIN && sun_zenith <= SKYSH_ZMAX) || !(turbidity >= SKYSH_TMIN && turbidity <= SKYSH_TMAX)
        || !(sun_azimuth - sun_azimuth == 0.0f))
        return SKYSH_FAIL(-1);
    if (SKYSH_LIGHTS % 2 == 0)
        return SKYSH_FAIL(-4);
    SKYSH_REAL phi = SKYSH_FMOD(sun_azimuth, SKYSH_TWO_PI);
    direction[0] = SKYSH_SIN(sun_zenith) * SKYSH_COS(phi);
    direction[1] = SKYSH_SIN(sun_zenith) * SKYSH_SIN(phi);
    direction[2] = SKYSH_COS(sun_zenith);
    skysh_sun_rgb(sun_zenith, direction[2], turbidity, rgb);
    return SKYSH_OK;
}

#ifdef SKYSH_ENGINE_COUNT
/*
 * Step 9, the rest of the engine's map (c_like_engine.h) on the radiance sh that skysh_evaluate gave in mode 2:
 * values[p] = the sum over the terms t with SKYSH_ENGINE_OUTPUT[t] = p of SKYSH_ENGINE_FACTOR[t] times coefficient
 * q / 3, channel q % 3 (q = SKYSH_ENGINE_INPUT[t]), plus SKYSH_ENGINE_OFFSET[p]; all zero unless ok.
 */
SKYSH_FN void skysh_engine_values(SKYSH_BOOL ok, SKYSH_RGB(sh[SKYSH_COUNT]), SKYSH_OUT SKYSH_REAL values[SKYSH_ENGINE_COUNT])
{
    for (int p = 0; p < SKYSH_ENGINE_COUNT; ++p)
        values[p] = 0.0f;
    if (!ok)
        return;
    for (int t = 0; t < SKYSH_ENGINE_TERMS; ++t) {
        int q = SKYSH_ENGINE_INPUT[t];
        values[SKYSH_ENGINE_OUTPUT[t]] += SKYSH_ENGINE_FACTOR[t] * sh[q / 3][q % 3];
    }
    for (int p = 0; p < SKYSH_ENGINE_COUNT; ++p)
        values[p] += SKYSH_ENGINE_OFFSET[p];
}
#endif
