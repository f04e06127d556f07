// Deterministic sums: work-group g of segment s (dimension 1) adds a fixed strided subset of
// the segment's terms per work-item, then a tree in local memory with a barrier at every level;
// the host adds the per-group partials in a fixed order. The local size must be a power of 2.
// Segment s covers terms[begin_s .. begin_s + count_s).
__kernel void reduce_segments(__global const real* terms, const int begin0, const int count0,
                              const int begin1, const int count1, const int begin2,
                              const int count2, __global real* partials,
                              __local real* scratch) {
  const int seg = get_group_id(1);
  const int begin = seg == 0 ? begin0 : seg == 1 ? begin1 : begin2;
  const int count = seg == 0 ? count0 : seg == 1 ? count1 : count2;
  const int lid = get_local_id(0);
  const int local_size = get_local_size(0);
  const int groups = get_num_groups(0);
  real s = 0;
  for (int i = get_group_id(0) * local_size + lid; i < count; i += groups * local_size)
    s += terms[begin + i];
  scratch[lid] = s;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int stride = local_size / 2; stride > 0; stride >>= 1) {
    if (lid < stride) scratch[lid] += scratch[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) partials[seg * groups + get_group_id(0)] = scratch[0];
}
