//! Four lanes of f32 (`F4`) and of u32 bit patterns (`U4`), for evaluating four noises at once.
//!
//! On x86-64 they are SSE2 registers: SSE2 is part of the x86-64 baseline, so there is no
//! runtime CPU-feature dispatch, and every operation here is one IEEE operation (or a bit
//! operation) lane by lane — no fused multiply-add, no approximation — so the results are the
//! same bits on every x86-64 CPU. Elsewhere they are plain arrays with the same operations,
//! which give the same bits again. (LLVM does not vectorise the noise kernel written on
//! arrays: it branches on the gradient choice lane by lane.)
//!
//! Owns: the lane types. Must not touch: what the lanes compute (`gradient`).

// SAFETY (every `unsafe` below): SSE2 is part of the x86-64 baseline, present on every x86-64
// CPU and enabled in every x86-64 build, and these intrinsics only compute on registers.
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Four f32 lanes.
#[derive(Clone, Copy, Debug)]
pub struct F4(
    #[cfg(target_arch = "x86_64")] __m128,
    #[cfg(not(target_arch = "x86_64"))] [f32; 4],
);

/// Four u32 lanes (bit patterns and masks).
#[derive(Clone, Copy, Debug)]
pub struct U4(
    #[cfg(target_arch = "x86_64")] __m128i,
    #[cfg(not(target_arch = "x86_64"))] [u32; 4],
);

#[cfg(target_arch = "x86_64")]
impl F4 {
    #[inline(always)]
    pub fn splat(x: f32) -> F4 {
        F4(unsafe { _mm_set1_ps(x) })
    }

    /// The lanes `x`, lowest first.
    #[inline(always)]
    pub fn from_array(x: [f32; 4]) -> F4 {
        // SAFETY: `_mm_loadu_ps` reads 16 bytes from any alignment; `x` has 16.
        F4(unsafe { _mm_loadu_ps(x.as_ptr()) })
    }

    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        // SAFETY: `__m128` and `[f32; 4]` have the same size, and every bit pattern is valid.
        unsafe { std::mem::transmute(self.0) }
    }

    #[inline(always)]
    pub fn add(self, o: F4) -> F4 {
        F4(unsafe { _mm_add_ps(self.0, o.0) })
    }

    #[inline(always)]
    pub fn sub(self, o: F4) -> F4 {
        F4(unsafe { _mm_sub_ps(self.0, o.0) })
    }

    #[inline(always)]
    pub fn mul(self, o: F4) -> F4 {
        F4(unsafe { _mm_mul_ps(self.0, o.0) })
    }

    #[inline(always)]
    pub fn bits(self) -> U4 {
        U4(unsafe { _mm_castps_si128(self.0) })
    }

    #[inline(always)]
    pub fn from_bits(u: U4) -> F4 {
        F4(unsafe { _mm_castsi128_ps(u.0) })
    }
}

#[cfg(target_arch = "x86_64")]
impl U4 {
    /// Every bit clear.
    // SAFETY: an all-zero `__m128i` is a valid value (four zero lanes).
    pub const ZERO: U4 = U4(unsafe { std::mem::zeroed() });

    #[inline(always)]
    pub fn splat(x: u32) -> U4 {
        U4(unsafe { _mm_set1_epi32(x as i32) })
    }

    /// The lanes `x`, lowest first.
    #[inline(always)]
    pub fn from_array(x: [u32; 4]) -> U4 {
        // SAFETY: `_mm_loadu_si128` reads 16 bytes from any alignment; `x` has 16.
        U4(unsafe { _mm_loadu_si128(x.as_ptr().cast()) })
    }

    /// The four 16-bit words of `h`, lowest first, one per lane.
    #[inline(always)]
    pub fn words(h: u64) -> U4 {
        U4(unsafe { _mm_unpacklo_epi16(_mm_cvtsi64_si128(h as i64), _mm_setzero_si128()) })
    }

    #[inline(always)]
    pub fn shl<const N: i32>(self) -> U4 {
        U4(unsafe { _mm_slli_epi32::<N>(self.0) })
    }

    #[inline(always)]
    pub fn shr<const N: i32>(self) -> U4 {
        U4(unsafe { _mm_srli_epi32::<N>(self.0) })
    }

    #[inline(always)]
    pub fn and(self, o: U4) -> U4 {
        U4(unsafe { _mm_and_si128(self.0, o.0) })
    }

    /// `self & !o`.
    #[inline(always)]
    pub fn and_not(self, o: U4) -> U4 {
        U4(unsafe { _mm_andnot_si128(o.0, self.0) })
    }

    #[inline(always)]
    pub fn or(self, o: U4) -> U4 {
        U4(unsafe { _mm_or_si128(self.0, o.0) })
    }

    #[inline(always)]
    pub fn xor(self, o: U4) -> U4 {
        U4(unsafe { _mm_xor_si128(self.0, o.0) })
    }

    /// All ones where the lanes are equal, zero elsewhere.
    #[inline(always)]
    pub fn eq(self, o: U4) -> U4 {
        U4(unsafe { _mm_cmpeq_epi32(self.0, o.0) })
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl F4 {
    #[inline(always)]
    pub fn splat(x: f32) -> F4 {
        F4([x; 4])
    }

    /// The lanes `x`, lowest first.
    #[inline(always)]
    pub fn from_array(x: [f32; 4]) -> F4 {
        F4(x)
    }

    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        self.0
    }

    #[inline(always)]
    pub fn add(self, o: F4) -> F4 {
        F4(std::array::from_fn(|k| self.0[k] + o.0[k]))
    }

    #[inline(always)]
    pub fn sub(self, o: F4) -> F4 {
        F4(std::array::from_fn(|k| self.0[k] - o.0[k]))
    }

    #[inline(always)]
    pub fn mul(self, o: F4) -> F4 {
        F4(std::array::from_fn(|k| self.0[k] * o.0[k]))
    }

    #[inline(always)]
    pub fn bits(self) -> U4 {
        U4(self.0.map(f32::to_bits))
    }

    #[inline(always)]
    pub fn from_bits(u: U4) -> F4 {
        F4(u.0.map(f32::from_bits))
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl U4 {
    /// Every bit clear.
    pub const ZERO: U4 = U4([0; 4]);

    #[inline(always)]
    pub fn splat(x: u32) -> U4 {
        U4([x; 4])
    }

    /// The lanes `x`, lowest first.
    #[inline(always)]
    pub fn from_array(x: [u32; 4]) -> U4 {
        U4(x)
    }

    /// The four 16-bit words of `h`, lowest first, one per lane.
    #[inline(always)]
    pub fn words(h: u64) -> U4 {
        U4(std::array::from_fn(|k| (h >> (16 * k)) as u32 & 0xffff))
    }

    #[inline(always)]
    pub fn shl<const N: i32>(self) -> U4 {
        U4(self.0.map(|x| x << N))
    }

    #[inline(always)]
    pub fn shr<const N: i32>(self) -> U4 {
        U4(self.0.map(|x| x >> N))
    }

    #[inline(always)]
    pub fn and(self, o: U4) -> U4 {
        U4(std::array::from_fn(|k| self.0[k] & o.0[k]))
    }

    /// `self & !o`.
    #[inline(always)]
    pub fn and_not(self, o: U4) -> U4 {
        U4(std::array::from_fn(|k| self.0[k] & !o.0[k]))
    }

    #[inline(always)]
    pub fn or(self, o: U4) -> U4 {
        U4(std::array::from_fn(|k| self.0[k] | o.0[k]))
    }

    #[inline(always)]
    pub fn xor(self, o: U4) -> U4 {
        U4(std::array::from_fn(|k| self.0[k] ^ o.0[k]))
    }

    /// All ones where the lanes are equal, zero elsewhere.
    #[inline(always)]
    pub fn eq(self, o: U4) -> U4 {
        U4(std::array::from_fn(|k| {
            if self.0[k] == o.0[k] { u32::MAX } else { 0 }
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_spread_a_hash_over_the_lanes() {
        let w = U4::words(0x0123_4567_89ab_cdef);
        let lanes = F4::from_bits(w).bits();
        let got: [u32; 4] = F4::from_bits(lanes).to_array().map(f32::to_bits);
        assert_eq!(got, [0xcdef, 0x89ab, 0x4567, 0x0123]);
    }

    #[test]
    fn lane_operations_are_lane_by_lane() {
        let a = F4::splat(1.5);
        let b = F4::splat(0.25);
        assert_eq!(a.add(b).to_array(), [1.75; 4]);
        assert_eq!(a.sub(b).to_array(), [1.25; 4]);
        assert_eq!(a.mul(b).to_array(), [0.375; 4]);
        let w = U4::words(0x0003_0002_0001_0000);
        let bits = |u: U4| F4::from_bits(u).to_array().map(f32::to_bits);
        assert_eq!(bits(w.eq(U4::splat(2))), [0, 0, u32::MAX, 0]);
        assert_eq!(bits(w.shl::<4>()), [0, 0x10, 0x20, 0x30]);
        assert_eq!(bits(w.shl::<4>().shr::<3>()), [0, 2, 4, 6]);
        assert_eq!(bits(w.and(U4::splat(1))), [0, 1, 0, 1]);
        assert_eq!(bits(w.and_not(U4::splat(1))), [0, 0, 2, 2]);
        assert_eq!(bits(w.or(U4::splat(4))), [4, 5, 6, 7]);
        assert_eq!(bits(w.xor(U4::splat(3))), [3, 2, 1, 0]);
    }
}
