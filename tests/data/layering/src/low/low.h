/* Includes its own layer's neighbour: a cycle with high.h. */
#include "high/high.h"
