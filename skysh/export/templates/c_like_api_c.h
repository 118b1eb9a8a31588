
/*
 * The C header's public functions (skysh/export/templates/c_like_api_c.h), after the kernel
 * (c_like_kernel.h), whose steps they call.
 */

/*
 * The sky's SH coefficients. Angles in radians. gibbs: apply the zonal sinc
 * filter; dering: the least window that keeps the irradiance non-negative (Sloan
 * 2017, SKYSH_DERING exports only); irradiance: convolve with the clamped cosine;
 * sun: add the sun's disk (a windowed delta); ground_albedo: NULL, or the RGB
 * albedo in [0, 1] of a Lambertian ground lit by the sky (and the sun with sun);
 * irradiance_table: SKYSH_BY_INTENT (the runtime's default), 0 or 1, as
 * skysh.SkySH.coefficients' None, False, True (skysh_use_table: the certified
 * irradiance table of 3-band exports for diffuse light, never negative).
 * Returns 0, or (out zeroed) -1 for a parameter outside the domain, NaN or inf,
 * -2 for dering without SKYSH_DERING, -3 for a ground albedo outside [0, 1],
 * -4 for the sun or the ground without its table (SKYSH_LIGHTS), -5 for an
 * irradiance_table refused (1 without SKYSH_IRRADIANCE_TABLE or with gibbs).
 */
static inline int skysh_coefficients(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth, int gibbs,
                                     int dering, int irradiance, int sun, const skysh_real *ground_albedo,
                                     int irradiance_table, skysh_real out[SKYSH_COUNT][3])
{
    return skysh_evaluate(sun_zenith, turbidity, sun_azimuth, gibbs, dering, sun, ground_albedo, irradiance_table,
                          irradiance ? 1 : 0, out);
}

/*
 * The sun as a directional light (skysh.SkySH.sun_light): the unit vector towards it (Z up) and its
 * RGB direct normal illuminance, lux, unclamped (slightly negative blue near the horizon). Returns
 * 0; -1 (zeroed) outside the domain, -4 without the file's sun table.
 */
static inline int skysh_sun_light(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth, skysh_real direction[3],
                                  skysh_real rgb[3])
{
    return skysh_evaluate_sun_light(sun_zenith, turbidity, sun_azimuth, direction, rgb);
}

#ifdef SKYSH_ENGINE_COUNT
/*
 * The numbers the engine of this header takes (its name and shape: the notice above):
 * skysh.engines.presets.convert(radiance, engine) flattened row-major. Arguments as skysh_coefficients
 * (engines light diffusely: SKYSH_BY_INTENT takes the irradiance table's radiance-equivalent as
 * irradiance does); returns 0, or -1 .. -5 (out zeroed) as skysh_coefficients.
 */
static inline int skysh_engine_coefficients(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth,
                                            int gibbs, int dering, int sun, const skysh_real *ground_albedo,
                                            int irradiance_table, skysh_real out[SKYSH_ENGINE_COUNT])
{
    skysh_real sh[SKYSH_COUNT][3];
    const int rc = skysh_evaluate(sun_zenith, turbidity, sun_azimuth, gibbs, dering, sun, ground_albedo,
                                  irradiance_table, 2, sh);
    skysh_engine_values(rc == 0, sh, out);
    return rc;
}
#endif
