
/*
 * The shaders' public functions (skysh/export/templates/c_like_api_shader.glsl, one file for GLSL and
 * HLSL, here with {{VEC3}} for RGB), after the kernel (c_like_kernel.h), whose steps they call.
 */

// The sky's SH coefficients. Angles in radians; sun adds the sun's disk, groundAlbedo
// (RGB in [0, 1], {{VEC3}}(0.0, 0.0, 0.0) for none) a Lambertian ground; irradianceTable SKYSH_BY_INTENT
// (the runtime's default), 0 or 1 as skysh.SkySH.coefficients' irradiance_table None, False,
// True. Returns false (coeffs zeroed) for a parameter outside the domain, dering without
// SKYSH_DERING (1..4 bands: 5..7 need the sampling certificate, C-only for its cost per call,
// skysh.export.dering.CERTIFICATE_COST, measured by python
// tests/export/test_export_dering_certificate.py), the sun or the ground without its table
// (SKYSH_LIGHTS), or an irradianceTable refused (1 without SKYSH_IRRADIANCE_TABLE or with gibbs).
bool skysh_coefficients(float sunZenith, float turbidity, float sunAzimuth, bool gibbs, bool dering, bool irradiance,
                        bool sun, {{VEC3}} groundAlbedo, int irradianceTable, out {{VEC3}} coeffs[SKYSH_COUNT])
{
    return skysh_evaluate(sunZenith, turbidity, sunAzimuth, gibbs, dering, sun, groundAlbedo, irradianceTable,
                          irradiance ? 1 : 0, coeffs);
}

// The sun as a directional light (skysh.SkySH.sun_light): the unit vector towards it (Z up) and its
// RGB direct normal illuminance, lux, unclamped (slightly negative blue near the horizon). Returns
// true; false (zeroed) outside the domain, or without the file's sun table.
bool skysh_sun_light(float sun_zenith, float turbidity, float sun_azimuth, out {{VEC3}} direction,
                     out {{VEC3}} rgb)
{
    return skysh_evaluate_sun_light(sun_zenith, turbidity, sun_azimuth, direction, rgb);
}

#ifdef SKYSH_ENGINE_COUNT
// The numbers the engine of this export takes (its name and shape: the notice above):
// skysh.engines.presets.convert(radiance, engine) flattened row-major (SKYSH_BY_INTENT: the
// irradiance table, as for irradiance). Returns false (values zeroed) as skysh_coefficients.
bool skysh_engine_coefficients(float sunZenith, float turbidity, float sunAzimuth, bool gibbs, bool dering, bool sun,
                               {{VEC3}} groundAlbedo, int irradianceTable, out float values[SKYSH_ENGINE_COUNT])
{
    {{VEC3}} sh[SKYSH_COUNT];
    bool ok = skysh_evaluate(sunZenith, turbidity, sunAzimuth, gibbs, dering, sun, groundAlbedo, irradianceTable, 2, sh);
    skysh_engine_values(ok, sh, values);
    return ok;
}
#endif
