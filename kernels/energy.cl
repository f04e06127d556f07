// Energy and mass-dot passes as one kernel each: element terms are computed and reduced per
// work-group in the same launch, one partial per group (no terms buffer, no separate reduce
// kernel): on PoCL each launch and wait costs more than the arithmetic of a small scene.
//
// The groups of a launch are split into consecutive segments; group g of segment s (of G_s
// groups, fixed by the host from the scene size) lets work-item l add the terms
// i = g L + l, g L + l + G_s L, ... of its segment, then reduces the group (workGroupSum) and
// writes partials[group id]. The host sums each segment's partials in group order, so every
// call adds the same terms in the same order: bit-identical results from run to run.

/// Segments of potential_partials: springs, tets, pins, vertices (external potential).
/// seg_begin.xyz = first group of segments 1, 2, 3 (segment 0 starts at group 0, segment 3 ends
/// with the launch); an empty segment has no groups.
__kernel void potential_partials(__global const real* x, const int n,
                                 const int num_springs, __global const int* spring_ends,
                                 __global const real* spring_params,
                                 const int num_tets, __global const int4* tet_vertices,
                                 __global const real* tet_rest,
                                 const int num_pins, __global const int* pin_vertex,
                                 __global const real* pin_stiffness,
                                 __global const real* pin_targets,
                                 __global const real* fext, const int4 seg_begin,
                                 __global real* partials, __local real* scratch) {
  const int group = get_group_id(0);
  const int seg = group < seg_begin.x ? 0 : group < seg_begin.y ? 1 : group < seg_begin.z ? 2 : 3;
  const int first = seg == 0 ? 0 : seg == 1 ? seg_begin.x : seg == 2 ? seg_begin.y : seg_begin.z;
  const int last = seg == 0 ? seg_begin.x : seg == 1 ? seg_begin.y : seg == 2 ? seg_begin.z
                                                                               : get_num_groups(0);
  const int local_size = get_local_size(0);
  const int stride = (last - first) * local_size;
  const int start = (group - first) * local_size + get_local_id(0);
  real s = 0;
  if (seg == 0) {
    for (int i = start; i < num_springs; i += stride)
      s += springEnergyAt(x, n, spring_ends, spring_params, i);
  } else if (seg == 1) {
    for (int i = start; i < num_tets; i += stride) s += tetEnergyAt(x, n, tet_vertices, tet_rest, i);
  } else if (seg == 2) {
    for (int i = start; i < num_pins; i += stride)
      s += pinEnergyAt(x, n, num_pins, pin_vertex, pin_stiffness, pin_targets, i);
  } else {
    for (int i = start; i < n; i += stride) s += externalEnergyAt(n, x, fext, i);
  }
  s = workGroupSum(s, scratch);
  if (get_local_id(0) == 0) partials[group] = s;
}

/// One segment: sum_j m_j a_j . b_j over the n vertices.
__kernel void mass_dot_partials(const int n, __global const real* masses, __global const real* a,
                                __global const real* b, __global real* partials,
                                __local real* scratch) {
  const int local_size = get_local_size(0);
  const int stride = get_num_groups(0) * local_size;
  real s = 0;
  for (int i = get_group_id(0) * local_size + get_local_id(0); i < n; i += stride)
    s += massDotTerm(n, masses, a, b, i);
  s = workGroupSum(s, scratch);
  if (get_local_id(0) == 0) partials[get_group_id(0)] = s;
}
