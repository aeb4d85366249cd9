/* Includes the layer below and, back, low.h. */
#include "base/base.h"
#include "low/low.h"
