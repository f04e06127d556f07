// Precision switch and small helpers shared by every kernel file. The host builds the program
// with -DSTABINT_DOUBLE or -DSTABINT_FLOAT (ocl::programOptions) and puts this file before the
// others.
//
// The constants the host shares with the kernels (pass flags PASS_*, collider shape codes
// COLLIDER_*, the collider geometry's and the segment table's layouts, the projections'
// thresholds, ...) are not defined in any kernel file: ocl::buildProgram puts the prelude
// generated from host/common/kernel_constants.hpp before every program's source, so each is declared
// once, there.
//
// Memory layouts:
//   state slots, external forces, rhs:  n by 3, column-major (all x, then all y, then all z),
//                                       the layout of Eigen::MatrixX3d;
//   element data (per type):           vertices K per element, coefficients of A_e R by K
//                                       row-major per element (or once when shared), params P
//                                       per element with the weight first (ElementBlock);
//   contributions:                      one packed 3-vector per contribution, numbered as in
//                                       ContributionCsr.
#if defined(STABINT_DOUBLE)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
typedef double3 real3;
#define REAL_EPSILON DBL_EPSILON
#elif defined(STABINT_FLOAT)
typedef float real;
typedef float3 real3;
#define REAL_EPSILON FLT_EPSILON
#else
#error "build with -DSTABINT_DOUBLE or -DSTABINT_FLOAT"
#endif

inline real3 loadRow(__global const real* m, int rows, int i) {
  return (real3)(m[i], m[rows + i], m[2 * rows + i]);
}

// |v| as sqrt(v.v), the same formula as the CPU reference (OpenCL's length() rescales).
inline real norm3(real3 v) { return sqrt(dot(v, v)); }
