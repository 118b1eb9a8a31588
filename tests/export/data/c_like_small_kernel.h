/*
 * The kernel of the C export as it stands, over the small data section (tests/export/test_templates.py
 * compiles tests/export/test_export_lights.py's harness with -DSKYSH_HEADER="c_like_small_kernel.h"):
 * the C words, the data, the deringing, the kernel and the C functions, each file as shipped in
 * skysh/export/templates/.
 * SKYSH_FLOAT (0 or 1) comes from the command line.
 */
#ifndef SKYSH_SMALL_KERNEL_H
#define SKYSH_SMALL_KERNEL_H
#include <math.h>
#include "c_like_words_c.h"
#include "c_like_small.h"
#include "c_like_dering3.h"
#include "c_like_kernel.h"
#include "c_like_api_c.h"
#endif
