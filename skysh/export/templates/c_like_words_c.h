/*
 * The words of the C-like kernel in C (skysh/export/templates/c_like_words_c.h): the kernel
 * (c_like_kernel.h) and its deringing (c_like_dering3.h) are written once over these names, which
 * c_like_words_glsl.glsl or c_like_words_hlsl.hlsl and c_like_words_shader.glsl define for the shaders
 * (sphericart's habit: one kernel, the language in macros), and c_like_words_math.h after these (sin ..
 * pow). Needs <math.h>; SKYSH_FLOAT 1 selects float for skysh_real.
 */
#if SKYSH_FLOAT
typedef float skysh_real;
#define SKYSH_SIN sinf /* float's names, before c_like_words_math.h's double ones */
#define SKYSH_COS cosf
#define SKYSH_TAN tanf
#define SKYSH_EXP expf
#define SKYSH_LOG logf
#define SKYSH_POW powf
#define SKYSH_FMOD fmodf
#else
typedef double skysh_real;
#define SKYSH_FMOD fmod
#endif
#define SKYSH_SHADER 0 /* 1 in GLSL and HLSL */
#define SKYSH_REAL skysh_real /* the tables' and the arithmetic's type */
#define SKYSH_BOOL int
#define SKYSH_STATUS int /* 0, or a negative code */
#define SKYSH_OK 0
#define SKYSH_FAIL(code) (code)
#define SKYSH_FN static inline
#define SKYSH_IN const
#define SKYSH_OUT
#define SKYSH_INOUT
#define SKYSH_RGB(name) skysh_real name[3]
#define SKYSH_ALBEDO const skysh_real * /* NULL: a black ground */
#define SKYSH_ALBEDO_AT(albedo, c) ((albedo) ? (albedo)[c] : 0.0f)
#define SKYSH_TO_REAL(x) ((skysh_real)(x))
#define SKYSH_CONST static const
#define SKYSH_ARRAY(type, size) {
#define SKYSH_END }
/* The deringing's words: double whatever skysh_real is. */
#define SKYSH_DREAL double
#define SKYSH_DERING_COEFFS(name) double name[SKYSH_DERING_COUNT][3]
#define SKYSH_DC(coeffs, k, ch) coeffs[k][ch]
#define SKYSH_TO_DREAL(x) ((double)(x))
#define SKYSH_TO_INT(x) ((int)(x))
#define SKYSH_MIN_INT(a, b) ((a) < (b) ? (a) : (b))
#define SKYSH_SQRT sqrt
#define SKYSH_ABS fabs
#define SKYSH_MAX fmax
#define SKYSH_MIN fmin
#define SKYSH_CBRT cbrt
