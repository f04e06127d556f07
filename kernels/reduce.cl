// Deterministic work-group sums: each work-item first adds a fixed subset of the terms (one
// element in the element pass, a strided subset in mass_dot_partials), then the group adds the work-items' sums with a tree in local
// memory, with a barrier at every level (on a CPU device one work-item adds them: below); the host
// adds the per-group partials in a fixed order.
// The local size must be a power of 2; every work-item of the group must call this.

/// Sum of `value` over the work-group (valid in every work-item). `scratch` holds local-size reals.
inline real workGroupSum(real value, __local real* scratch) {
  const int lid = get_local_id(0);
  scratch[lid] = value;
  barrier(CLK_LOCAL_MEM_FENCE);
#ifdef STABINT_GROUP_SUM_SERIAL
  // On a CPU device (built with STABINT_GROUP_SUM_SERIAL by the host) the work-items of a group
  // run as one loop per region between barriers, so the tree's log2(local size) levels cost a
  // loop over the whole group each (on PoCL they doubled an element pass that sums energies).
  // Here one work-item adds the values in 16 interleaved chains, then the chains in a tree:
  // one region, a fixed order.
  if (lid == 0) {
    const int size = get_local_size(0);
    if (size >= 16) {
      real acc[16];
      for (int j = 0; j < 16; ++j) acc[j] = scratch[j];
      for (int i = 16; i < size; i += 16)
        for (int j = 0; j < 16; ++j) acc[j] += scratch[i + j];
      for (int width = 8; width > 0; width >>= 1)
        for (int j = 0; j < width; ++j) acc[j] += acc[j + width];
      scratch[0] = acc[0];
    } else {
      real sum = scratch[0];
      for (int i = 1; i < size; ++i) sum += scratch[i];
      scratch[0] = sum;
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
#else
  for (int stride = get_local_size(0) / 2; stride > 0; stride >>= 1) {
    if (lid < stride) scratch[lid] += scratch[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
#endif
  return scratch[0];
}
