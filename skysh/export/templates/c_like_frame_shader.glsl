/*
{{NOTICE}}
Paste into a shader (no #version line; GLSL 3.30 / ES 3.00 or later, or HLSL
SM 4+). For 4 or more bands the table is large for a constant array: move it
to a uniform or storage buffer with the same layout if the compiler balks.
The code is skysh's C-like kernel, written once for C, GLSL and HLSL over the
SKYSH_ words defined first.
*/
{{BODY}}
