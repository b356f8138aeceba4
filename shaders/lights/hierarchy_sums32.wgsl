// The hierarchy's hash-table slots as 32-bit atomics (every adapter): 16 words a slot, the key
// in word 0, sum k (0..5) in words 1 + 2k (low) and 2 + 2k (high), a 64-bit fixed-point sum
// carried by hand from the low word into the high one. Its twin, hierarchy_sums64.wgsl, does
// each add in one 64-bit atomic; shaders/lights/hierarchy.wgsl (after this file) uses them.

@group(0) @binding(4) var<storage, read_write> slots: array<atomic<u32>>;

const SLOT_WORDS: u32 = 16u;
const TWO32: f32 = 4294967296.0;

// Takes slot `at` for `key` where it is empty: 0 where it was, else the key it holds.
fn slot_claim(at: u32, key: u32) -> u32 {
    loop {
        let r = atomicCompareExchangeWeak(&slots[at * SLOT_WORDS], 0u, key);
        if r.exchanged {
            return 0u;
        }
        // A weak exchange that failed on an empty slot is tried again.
        if r.old_value != 0u {
            return r.old_value;
        }
    }
    return 0u;
}

fn slot_key(at: u32) -> u32 {
    return atomicLoad(&slots[at * SLOT_WORDS]);
}

fn sum_read(at: u32, k: u32) -> f32 {
    let i = at * SLOT_WORDS + 1u + 2u * k;
    return f32(atomicLoad(&slots[i + 1u])) * TWO32 + f32(atomicLoad(&slots[i]));
}

fn sum_read_signed(at: u32, k: u32) -> f32 {
    let i = at * SLOT_WORDS + 1u + 2u * k;
    let lo = atomicLoad(&slots[i]);
    let hi = atomicLoad(&slots[i + 1u]);
    if hi < 0x80000000u {
        return f32(hi) * TWO32 + f32(lo);
    }
    let lo_m = ~lo + 1u;
    let hi_m = ~hi + select(0u, 1u, lo == 0u);
    return -(f32(hi_m) * TWO32 + f32(lo_m));
}

// A 64-bit fixed-point term or sum held in registers, (low, high) words: a term splat adds,
// or what a cell sums over its lights before one atomic add a node (hierarchy.wgsl's
// cell_splat).
alias Term = vec2<u32>;

fn term_zero() -> Term {
    return vec2<u32>(0u);
}

// The integer of a non-negative term.
fn term_of(v: f32) -> Term {
    let hi = floor(v / TWO32);
    return vec2<u32>(u32(v - hi * TWO32), u32(hi));
}

// The integer of a signed term (two's complement).
fn term_of_signed(v: f32) -> Term {
    if v >= 0.0 {
        return term_of(v);
    }
    let m = term_of(-v);
    return vec2<u32>(~m.x + 1u, ~m.y + select(0u, 1u, m.x == 0u));
}

fn term_add(a: Term, b: Term) -> Term {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// Adds a term to sum k of slot `at`, the carry from the low word into the high one by hand.
fn sum_add_term(at: u32, k: u32, t: Term) {
    let i = at * SLOT_WORDS + 1u + 2u * k;
    let old = atomicAdd(&slots[i], t.x);
    let carry = select(0u, 1u, old + t.x < old);
    let high = t.y + carry;
    if high != 0u {
        atomicAdd(&slots[i + 1u], high);
    }
}
