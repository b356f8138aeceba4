// cull.clustered.order's workgroup-memory capacity where a workgroup has less than 32 KB.
const ORDER_LOCAL: u32 = 2048u;
