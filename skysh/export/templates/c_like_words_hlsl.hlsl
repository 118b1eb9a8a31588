/*
 * The words of the C-like kernel that are HLSL's own (skysh/export/templates/c_like_words_hlsl.hlsl;
 * HLSL shader model 4 or later), before those it shares with GLSL (c_like_words_shader.glsl).
 */
#define SKYSH_RGB(name) float3 name
#define SKYSH_ALBEDO float3
#define SKYSH_CONST static const
#define SKYSH_ARRAY(type, size) {
#define SKYSH_END }
#define SKYSH_FMOD fmod
