// cull.clustered.order's workgroup-memory capacity where a workgroup has 32 KB: 8,191 light
// indices and the list length fill it exactly.
const ORDER_LOCAL: u32 = 8191u;
