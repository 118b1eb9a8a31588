/*
 * The data section of the C, GLSL and HLSL exports (skysh/export/templates/c_like_data.h): numbers
 * only, written by skysh.export.c_like from the coefficient file, skysh.domain, skysh.model.preetham,
 * skysh.model.ground and skysh.lighting.lights, for c_like_kernel.h.
 *
 * Sizes and switches: SKYSH_BANDS N (l = 0 .. N - 1); SKYSH_COUNT N * N; SKYSH_HALF the stored (m >= 0)
 * coefficients; SKYSH_ROWS the table's rows (the stored coefficients; one band: and the unfiltered
 * c_10, for the ground); SKYSH_DX, SKYSH_DY the Chebyshev degrees in x (sun zenith) and y (log
 * turbidity); SKYSH_SUN_DX, SKYSH_SUN_DY the sun table's, in its x (air mass) and y (turbidity);
 * SKYSH_DERING 1 where the dering option works (C: 1..7 bands; GLSL, HLSL: 1..4); SKYSH_LIGHTS 1 the sun, 2 the
 * ground, 3 both; SKYSH_IRRADIANCE_TABLE 1 where the certified irradiance table is here;
 * SKYSH_BY_INTENT the irradiance_table value that means the runtime's default.
 *
 * Numbers: the domain, sun zenith SKYSH_ZMIN .. SKYSH_ZMAX rad and turbidity SKYSH_TMIN .. SKYSH_TMAX;
 * x = sun_zenith SKYSH_X_SCALE - SKYSH_X_SHIFT and y = log(turbidity) SKYSH_Y_SCALE - SKYSH_Y_SHIFT,
 * clamped to [-1, 1] (skysh.domain.SKY); the sun table's x = (m - SKYSH_SUN_M0) SKYSH_SUN_X_SCALE - 1
 * of Kasten's air mass m = 1 / (cos ts + SKYSH_KASTEN_A (SKYSH_KASTEN_B - ts SKYSH_DEG)^SKYSH_KASTEN_NEG_C)
 * and y = (T - SKYSH_SUN_TMIN) SKYSH_SUN_Y_SCALE - 1 (skysh.domain.SUN); the zenith luminance
 * Y_z = 1000 ((SKYSH_ZENITH_A T - SKYSH_ZENITH_B) tan chi - SKYSH_ZENITH_C T + SKYSH_ZENITH_D),
 * chi = (SKYSH_ZENITH_CHI - T / 120) (SKYSH_PI - 2 ts) (Preetham 1999); SKYSH_TWO_PI, SKYSH_INV_PI;
 * SKYSH_HF = sqrt(4 pi / 3), the horizontal irradiance of c_10 (skysh.model.ground); SKYSH_SUN_CLAMP,
 * the least colour of the sun's disk (skysh.lighting.lights).
 */
{{DEFINES}}
#define SKYSH_TERMS ((SKYSH_DX + 1) * (SKYSH_DY + 1))

/* [(i (SKYSH_DY + 1) + j) 3 SKYSH_ROWS + 3 r + c]: the coefficient of T_i(x) T_j(y) for stored coefficient r
 * (l = 0, 1, 1, 2, 2, 2, ... with m = 0 .. l; one band: r = 1 is the unfiltered c_10) and channel c (R, G, B),
 * over the luminance scale: term-major, the 3 SKYSH_ROWS outputs of one term contiguous (one vectorisable pass
 * a term in c_like_kernel.h's skysh_rows; a shader that moves it to a buffer keeps this layout). */
SKYSH_CONST SKYSH_REAL SKYSH_TABLE[SKYSH_ROWS * SKYSH_TERMS * 3] = SKYSH_ARRAY(SKYSH_REAL, SKYSH_ROWS * SKYSH_TERMS * 3)
    {{TABLE}}
SKYSH_END;

/* The zonal Gibbs factors sinc(pi l / N) (Habel eq. 5) and the clamped-cosine factors A_l. */
SKYSH_CONST SKYSH_REAL SKYSH_GIBBS[SKYSH_BANDS] = SKYSH_ARRAY(SKYSH_REAL, SKYSH_BANDS) {{GIBBS}} SKYSH_END;
SKYSH_CONST SKYSH_REAL SKYSH_LOBE[SKYSH_BANDS] = SKYSH_ARRAY(SKYSH_REAL, SKYSH_BANDS) {{LOBE}} SKYSH_END;

/* [2 k + s]: the Perez A .. E (k) of luminance as slope (s = 0) and intercept (s = 1) in turbidity (Preetham 1999). */
SKYSH_CONST SKYSH_REAL SKYSH_PEREZ_Y[10] = SKYSH_ARRAY(SKYSH_REAL, 10)
    {{PEREZ}}
SKYSH_END;

#if SKYSH_IRRADIANCE_TABLE
/* [(i (SKYSH_DY + 1) + j) 3 SKYSH_HALF + 3 r + c]: the certified irradiance table, E_lm / A_l of the
 * m >= 0 rows over the luminance scale (docs/irradiance.md), term-major as SKYSH_TABLE. */
SKYSH_CONST SKYSH_REAL SKYSH_IRRADIANCE[SKYSH_HALF * SKYSH_TERMS * 3] = SKYSH_ARRAY(SKYSH_REAL, SKYSH_HALF * SKYSH_TERMS * 3)
    {{IRRADIANCE}}
SKYSH_END;
#endif

/* [3 (i (SKYSH_SUN_DY + 1) + j) + c]: ln X, ln Y, ln Z (ln lux) of T_i(x) T_j(y), the sun's direct normal illuminance. */
SKYSH_CONST SKYSH_REAL SKYSH_SUN_TABLE[(SKYSH_SUN_DX + 1) * (SKYSH_SUN_DY + 1) * 3] =
    SKYSH_ARRAY(SKYSH_REAL, (SKYSH_SUN_DX + 1) * (SKYSH_SUN_DY + 1) * 3)
    {{SUN_TABLE}}
SKYSH_END;

/* XYZ -> linear RGB of the coefficient file, row-major. */
SKYSH_CONST SKYSH_REAL SKYSH_SUN_RGB[9] = SKYSH_ARRAY(SKYSH_REAL, 9)
    {{SUN_RGB}}
SKYSH_END;

/* [2 N r + q]: the windowed SH Ybar_r(ts) of the sun's direction (stored r, azimuth 0) over cos(q ts), then sin((q - N) ts). */
SKYSH_CONST SKYSH_REAL SKYSH_SUN_TRIG[SKYSH_HALF * 2 * SKYSH_BANDS] = SKYSH_ARRAY(SKYSH_REAL, SKYSH_HALF * 2 * SKYSH_BANDS)
    {{SUN_TRIG}}
SKYSH_END;

/* The (l, 0) SH of a uniform lower hemisphere of unit radiance. */
SKYSH_CONST SKYSH_REAL SKYSH_GROUND[SKYSH_BANDS] = SKYSH_ARRAY(SKYSH_REAL, SKYSH_BANDS) {{GROUND}} SKYSH_END;
