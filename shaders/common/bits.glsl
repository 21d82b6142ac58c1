// Bit sets of at most 32 members (a uint) walked lowest first: the lights a loop visits (common/lighting.glsl),
// the glass's wet taps (windshield/glass.frag). A loop over a set's bits makes as many trips as the largest set
// among the fragments run together (a GPU warp, llvmpipe's 8-wide fragment code), and none where every set
// is empty.

// The lowest bit of mask, taken out of it (GLSL 3.30 has no findLSB: a power of two's float exponent is exact).
int pop_bit(inout uint mask) {
    uint low = mask & (~mask + 1u);
    mask ^= low;
    return int(floatBitsToUint(float(low)) >> 23u) - 127;
}
