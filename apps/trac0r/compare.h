/* compare.h - reading the images `trac0r compare` compares (the metrics themselves
 * are libtrac0r's, post.h). */
#ifndef TRAC0R_COMPARE_H
#define TRAC0R_COMPARE_H

#include "trac0r/trac0r.h"

/* Reads a .pfm (linear) or .png (sRGB, decoded to linear) image. */
int compare_load(const char *path, tr_image *img, tr_error *err);

#endif
