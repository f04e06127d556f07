// Precision switch and small helpers shared by every kernel file. The host builds the program
// with -DSTABINT_DOUBLE or -DSTABINT_FLOAT and prepends this file to the others.
//
// Memory layouts:
//   state slots, external forces, rhs:  n by 3, column-major (all x, then all y, then all z),
//                                       the layout of Eigen::MatrixX3d;
//   pin targets:                        #pins by 3, column-major likewise;
//   contributions:                      one packed 3-vector per contribution (vload3/vstore3),
//                                       numbered as in ContributionCsr.
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

// What an element kernel writes per contribution: w_e A_e^T p_e (the local step's share of the
// global right-hand side) or w_e A_e^T (p_e - A_e x) (the element's force, -grad E_e).
#define MODE_PROJECTION 0
#define MODE_FORCE 1

inline real3 loadRow(__global const real* m, int rows, int i) {
  return (real3)(m[i], m[rows + i], m[2 * rows + i]);
}

// |v| as sqrt(v.v), the same formula as the CPU reference (OpenCL's length() rescales).
inline real norm3(real3 v) { return sqrt(dot(v, v)); }
