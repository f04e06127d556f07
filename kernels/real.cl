// Precision switch and small helpers shared by every kernel file. The host builds the program
// with -DSTABINT_DOUBLE or -DSTABINT_FLOAT and prepends this file to the others.
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

// What an element pass computes, as bit flags (PassFlags in host/elements/element_type.hpp):
// per contribution w_e A_e^T p_e (the local step's share of the global right-hand side) or
// w_e A_e^T (p_e - A_e x) (the element's force, -grad E_e); and per work-group the summed
// energies w_e/2 ||A_e x - p_e||^2; or each element's energy on its own (PASS_ENERGY_PER_ELEMENT,
// for the per-scene sums of a batch, segments.cl: a group's sum would mix scenes).
#define PASS_PROJECTION 1
#define PASS_FORCE 2
#define PASS_ENERGY 4
#define PASS_ENERGY_PER_ELEMENT 8

inline real3 loadRow(__global const real* m, int rows, int i) {
  return (real3)(m[i], m[rows + i], m[2 * rows + i]);
}

// |v| as sqrt(v.v), the same formula as the CPU reference (OpenCL's length() rescales).
inline real norm3(real3 v) { return sqrt(dot(v, v)); }
