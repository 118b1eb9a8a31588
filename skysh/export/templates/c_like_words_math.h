/*
 * The math words of the C-like kernel (skysh/export/templates/c_like_words_math.h), after each
 * language's words: the C library's names (sin .. pow), which GLSL and HLSL share. A language that names
 * them otherwise defines them first (c_like_words_c.h's float build: sinf ...); SKYSH_FMOD is each
 * language's own (fmod, GLSL's mod).
 */
#ifndef SKYSH_SIN
#define SKYSH_SIN sin
#define SKYSH_COS cos
#define SKYSH_TAN tan
#define SKYSH_EXP exp
#define SKYSH_LOG log
#define SKYSH_POW pow
#endif
