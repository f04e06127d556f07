// Per-scene sums of a batch (docs/batch_design.md, "Backend operations"): the backend's scene is a
// concatenation of scenes, and each sum here is one scene's alone. One work-item per scene adds
// that scene's terms in a fixed order (deterministic, independent of the launch geometry): a
// work-group per scene would leave most of its items idle for the small scenes batches are made
// of (a 10-particle chain has 11 elements), and a group's sum over a range of elements, as the
// single-value reductions form it, would mix neighbouring scenes.
//
// The segment table holds, per scene, SEGMENT_ROW_HEAD + SEGMENT_ROW_PER_BLOCK B ints (the
// prelude's layout, host/common/kernel_constants.hpp): its first particle and particle count, then for
// each of the B element blocks the first index of its elements' energies (written by element_pass
// with PASS_ENERGY_PER_ELEMENT) and their count.

/// Kahan's compensated sum: one work-item adds a whole scene's terms in turn, and the
/// compensation keeps the error at a few units of round-off whatever the scene's size (a plain
/// running sum in float would lose digits in proportion to the count).
inline void addCompensated(real value, real* sum, real* compensation) {
  const real y = value - *compensation;
  const real t = *sum + y;
  *compensation = (t - *sum) - y;
  *sum = t;
}

/// out[SEGMENT_ENERGIES s + SEGMENT_INTERNAL, SEGMENT_PINS, SEGMENT_EXTERNAL] = scene s's internal
/// energy, pin energy and external potential at x (the external one from f_ext . x per vertex, as
/// element_pass's vertex groups form it).
__kernel void segment_energies(const int segments, const int blocks, __global const int* table,
                               __global const int* block_is_pins,
                               __global const real* element_energies, const int n,
                               __global const real* x, __global const real* fext,
                               __global real* out) {
  const int s = get_global_id(0);
  if (s >= segments) return;
  __global const int* row = table + (SEGMENT_ROW_HEAD + SEGMENT_ROW_PER_BLOCK * blocks) * s;
  real internal = 0, internal_c = 0, pins = 0, pins_c = 0, external = 0, external_c = 0;
  for (int b = 0; b < blocks; ++b) {
    __global const int* range = row + SEGMENT_ROW_HEAD + SEGMENT_ROW_PER_BLOCK * b;
    const int begin = range[0], end = begin + range[1];
    if (block_is_pins[b]) {
      for (int e = begin; e < end; ++e) addCompensated(element_energies[e], &pins, &pins_c);
    } else {
      for (int e = begin; e < end; ++e) addCompensated(element_energies[e], &internal, &internal_c);
    }
  }
  const int first = row[0], last = row[0] + row[1];
  for (int j = first; j < last; ++j)
    addCompensated(externalEnergyAt(n, x, fext, j), &external, &external_c);
  out[SEGMENT_ENERGIES * s + SEGMENT_INTERNAL] = internal;
  out[SEGMENT_ENERGIES * s + SEGMENT_PINS] = pins;
  out[SEGMENT_ENERGIES * s + SEGMENT_EXTERNAL] = external;
}

/// out[s] = sum over scene s's particles of m_j a_j . b_j.
__kernel void segment_mass_dots(const int segments, const int blocks, __global const int* table,
                                const int n, __global const real* masses,
                                __global const real* a, __global const real* b,
                                __global real* out) {
  const int s = get_global_id(0);
  if (s >= segments) return;
  __global const int* row = table + (SEGMENT_ROW_HEAD + SEGMENT_ROW_PER_BLOCK * blocks) * s;
  real sum = 0, c = 0;
  const int first = row[0], last = row[0] + row[1];
  for (int j = first; j < last; ++j) addCompensated(massDotTerm(n, masses, a, b, j), &sum, &c);
  out[s] = sum;
}
