// The hierarchy's hash-table slots as 64-bit atomics (SHADER_INT64_ATOMIC_ALL_OPS): 8 64-bit
// words a slot (the same 64 bytes as hierarchy_sums32.wgsl's 16), the key in word 0 (its low
// 32 bits where the 32-bit layout has it), sum k (0..5) in word 1 + k, each add one atomic.
// The sums are the same fixed-point integers as the 32-bit layout's; shaders/lights/hierarchy.wgsl
// (after this file) uses them.

@group(0) @binding(4) var<storage, read_write> slots: array<atomic<u64>>;

const SLOT_WORDS64: u32 = 8u;

// Takes slot `at` for `key` where it is empty: 0 where it was, else the key it holds.
fn slot_claim(at: u32, key: u32) -> u32 {
    loop {
        let r = atomicCompareExchangeWeak(&slots[at * SLOT_WORDS64], 0lu, u64(key));
        if r.exchanged {
            return 0u;
        }
        // A weak exchange that failed on an empty slot is tried again.
        if r.old_value != 0lu {
            return u32(r.old_value);
        }
    }
    return 0u;
}

fn slot_key(at: u32) -> u32 {
    return u32(atomicLoad(&slots[at * SLOT_WORDS64]));
}

fn sum_read(at: u32, k: u32) -> f32 {
    return f32(atomicLoad(&slots[at * SLOT_WORDS64 + 1u + k]));
}

fn sum_read_signed(at: u32, k: u32) -> f32 {
    return f32(bitcast<i64>(atomicLoad(&slots[at * SLOT_WORDS64 + 1u + k])));
}

// A 64-bit fixed-point term or sum held in registers: a term splat adds, or what a cell sums
// over its lights before one atomic add a node (hierarchy.wgsl's cell_splat; addition wraps, as
// the atomics do).
alias Term = u64;

fn term_zero() -> Term {
    return 0lu;
}

fn term_of(v: f32) -> Term {
    return u64(v);
}

fn term_of_signed(v: f32) -> Term {
    return bitcast<u64>(i64(v));
}

fn term_add(a: Term, b: Term) -> Term {
    return a + b;
}

// Adds a term to sum k of slot `at`.
fn sum_add_term(at: u32, k: u32, t: Term) {
    atomicAdd(&slots[at * SLOT_WORDS64 + 1u + k], t);
}
