// The environment (light arriving from infinitely far away) as host and
// kernels share it: a constant radiance, or an equirectangular map sampled by
// luminance x sin(theta). The map's arrays travel separately (see
// kernels/lights/environment.cl for the direction convention):
//   texels          float4[width * height]   linear RGB radiance, row-major, row 0 = +Y pole; w unused
//   marginal_cdf    float[height + 1]        rows: cdf[0] = 0, cdf[height] = 1
//   conditional_cdf float[height * (width + 1)]  per row, columns: [0] = 0, [width] = 1
#ifndef WT_SHARED_ENVIRONMENT_H
#define WT_SHARED_ENVIRONMENT_H

#include "shared/types.h"

#define WT_ENV_CONSTANT 0     ///< no map: `color` from every direction, uniform sphere sampling
#define WT_ENV_MAP 1          ///< equirectangular map, importance sampled by luminance x sin(theta)
#define WT_ENV_MAP_UNIFORM 2  ///< a map with no energy (all black): uniform sphere sampling, never NaN

/// Environment header, 48 bytes, passed to kernels by value.
typedef struct WtEnvironment {
  WtVec4 color;        ///< WT_ENV_CONSTANT: radiance from every direction, nits per channel (before `intensity`); w unused
  float intensity;     ///< scale on every returned radiance (map texels and `color`), unitless
  float rotation;      ///< radians about world +Y; positive turns the map counter-clockwise seen from above
  float cos_rotation;  ///< cos(rotation), so kernels need no trigonometry for it
  float sin_rotation;  ///< sin(rotation)
  wt_uint mode;        ///< WT_ENV_*
  wt_uint width;       ///< map texels per row (longitude); 1 for WT_ENV_CONSTANT (dummy arrays)
  wt_uint height;      ///< map rows (latitude); 1 for WT_ENV_CONSTANT
  wt_uint pad0;
} WtEnvironment;

#endif  // WT_SHARED_ENVIRONMENT_H
