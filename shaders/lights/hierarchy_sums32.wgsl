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

// Adds a non-negative term to sum k of slot `at`.
fn sum_add(at: u32, k: u32, v: f32) {
    let i = at * SLOT_WORDS + 1u + 2u * k;
    let hi = floor(v / TWO32);
    let lo = u32(v - hi * TWO32);
    let old = atomicAdd(&slots[i], lo);
    let carry = select(0u, 1u, old + lo < old);
    let high = u32(hi) + carry;
    if high != 0u {
        atomicAdd(&slots[i + 1u], high);
    }
}

// Adds a signed term to sum k of slot `at` (64-bit two's complement).
fn sum_add_signed(at: u32, k: u32, v: f32) {
    if v >= 0.0 {
        sum_add(at, k, v);
        return;
    }
    let i = at * SLOT_WORDS + 1u + 2u * k;
    let m = -v;
    let hi = floor(m / TWO32);
    let lo = u32(m - hi * TWO32);
    let lo_n = ~lo + 1u;
    let hi_n = ~u32(hi) + select(0u, 1u, lo == 0u);
    let old = atomicAdd(&slots[i], lo_n);
    let carry = select(0u, 1u, old + lo_n < old);
    atomicAdd(&slots[i + 1u], hi_n + carry);
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
