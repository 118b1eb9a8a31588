/*
{{NOTICE}}
A C99 header: #include "sky_sh.h" in any number of C or C++ files and link
with -lm. Every function is static inline and every table static const; the
code is skysh's C-like kernel, written once for C, GLSL and HLSL over the
SKYSH_ words defined first.
*/
#ifndef SKYSH_SKY_SH_H
#define SKYSH_SKY_SH_H

#include <math.h>

#define SKYSH_FLOAT {{FLOAT}} /* 1: skysh_real is float (skysh export --c-real float), 0: double */
{{BODY}}
#endif /* SKYSH_SKY_SH_H */
