// Deterministic work-group sums: each work-item first adds a fixed subset of the terms (one
// element in the element pass, a strided subset in mass_dot_partials), then the group adds the work-items' sums with a tree in local
// memory, with a barrier at every level; the host adds the per-group partials in a fixed order.
// The local size must be a power of 2; every work-item of the group must call this.

/// Sum of `value` over the work-group (valid in every work-item). `scratch` holds local-size reals.
inline real workGroupSum(real value, __local real* scratch) {
  const int lid = get_local_id(0);
  scratch[lid] = value;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int stride = get_local_size(0) / 2; stride > 0; stride >>= 1) {
    if (lid < stride) scratch[lid] += scratch[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  return scratch[0];
}
