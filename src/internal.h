/* Every internal header at once, for the tests and tools that reach the
 * library's internals.  The library's own files include what they use. */
#ifndef VS_INTERNAL_H
#define VS_INTERNAL_H

#include "camera.h"
#include "classify.h"
#include "context.h"
#include "gaussian.h"
#include "light.h"
#include "raycast.h"
#include "timing.h"
#include "volume.h"

#endif
