/*
 * fdi_prewarp.h - internal: checked pre-warped angular frequency for the bilinear transform.
 * W = (2/dt) * tan(pi * cutoff_hz * dt). Cost: one tanf. Not part of the public API.
 */
#ifndef FDI_PREWARP_H
#define FDI_PREWARP_H

#include "fdi_status.h"

/* FDI_OK and *w > 0 iff dt > 0, 0 < cutoff_hz < 0.5/dt and all values finite. */
fdi_status_t fdi_prewarp_omega(float dt, float cutoff_hz, float *w);

#endif /* FDI_PREWARP_H */
