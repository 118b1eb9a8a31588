/*
 * The words of the C-like kernel that are GLSL's own (skysh/export/templates/c_like_words_glsl.glsl;
 * GLSL 3.30, ES 3.00 or later), before those it shares with HLSL (c_like_words_shader.glsl).
 */
#define SKYSH_RGB(name) vec3 name
#define SKYSH_ALBEDO vec3
#define SKYSH_CONST const
#define SKYSH_ARRAY(type, size) type[size](
#define SKYSH_END )
#define SKYSH_FMOD mod
