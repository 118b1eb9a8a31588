/*
 * The words of the C-like kernel in GLSL and HLSL alike (skysh/export/templates/c_like_words_shader.glsl),
 * after each shader language's own (c_like_words_glsl.glsl, c_like_words_hlsl.hlsl): the names
 * c_like_words_c.h defines for C, here float32 throughout.
 */
#define SKYSH_SHADER 1
#define SKYSH_REAL float
#define SKYSH_BOOL bool
#define SKYSH_STATUS bool
#define SKYSH_OK true
#define SKYSH_FAIL(code) false
#define SKYSH_FN
#define SKYSH_IN in
#define SKYSH_OUT out
#define SKYSH_INOUT inout
#define SKYSH_ALBEDO_AT(albedo, c) (albedo)[c]
#define SKYSH_TO_REAL(x) float(x)
#define SKYSH_DREAL float
#define SKYSH_DERING_COEFFS(name) float name[3 * SKYSH_DERING_COUNT]
#define SKYSH_DC(coeffs, k, ch) coeffs[(k) * 3 + (ch)]
#define SKYSH_TO_DREAL(x) float(x)
#define SKYSH_TO_INT(x) int(x)
#define SKYSH_MIN_INT(a, b) min(a, b)
#define SKYSH_SQRT sqrt
#define SKYSH_ABS abs
#define SKYSH_MAX max
#define SKYSH_MIN min
#define SKYSH_CBRT(x) pow(x, 1.0 / 3.0)
