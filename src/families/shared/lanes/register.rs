//! What the one-register vector types ([`super::avx2::F64x4`], [`super::avx512::F64x8`]) write
//! alike, as macros over their intrinsics: the operators, and the [`Lane`] methods that are one
//! intrinsic each. Each type's module keeps what differs (its masks, `blend`, the bit shift). The
//! callers import [`Lane`], `std::ops`' traits and `std::arch::x86_64::*`; the intrinsics are
//! sound where the type's module says its values exist only on CPUs with their feature.
//!
//! [`Lane`]: super::vector::Lane

/// The operators of a one-register vector type `$t` (`avx2::F64x4`, `avx512::F64x8`), each by
/// one intrinsic: `+ − × ÷` lane-wise, also with an `f64` on the right (splat to every lane),
/// `& | ^` on the bits, and `−x`, `!x` by xor with the sign bit and with all ones. The caller
/// imports [`Lane`](super::vector::Lane) and `std::ops`' traits; the intrinsics are sound where
/// the type's module says its values exist only on CPUs with their feature.
macro_rules! register_operators {
    ($t:ident {
        arithmetic $($trait:ident::$method:ident = $intrinsic:ident),*;
        bits $($btrait:ident::$bmethod:ident = $bintrinsic:ident),*;
    }) => {
        $(
            register_operators!(@lanewise $t, $trait, $method, $intrinsic);
            impl $trait<f64> for $t {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: f64) -> Self {
                    self.$method(Self::splat(o))
                }
            }
        )*
        $(register_operators!(@lanewise $t, $btrait, $bmethod, $bintrinsic);)*
        impl Neg for $t {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                self ^ Self::splat(-0.0)
            }
        }
        impl Not for $t {
            type Output = Self;
            #[inline(always)]
            fn not(self) -> Self {
                self ^ Self::splat(f64::from_bits(u64::MAX))
            }
        }
    };
    (@lanewise $t:ident, $trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for $t {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                // SAFETY: values of the type exist only on CPUs with the intrinsic's feature.
                $t(unsafe { $intrinsic(self.0, o.0) })
            }
        }
    };
}
pub(crate) use register_operators;

/// The [`Lane`](super::vector::Lane) items of a one-register type `$t` over `$reg` with `$n`
/// lanes that are one intrinsic each: `LANES`, `Array`, `ZERO`, `ONE`, `splat`, `new` (an
/// unaligned load), `to_array` (an unaligned store), the six compares (`$wrap` makes the type
/// from the compare intrinsic's result), `abs` (and-not with the sign bit), `sqrt`, `round` (to
/// nearest, ties to even), `min` and `max`. Invoked inside the type's `impl Lane`.
macro_rules! register_lane_items {
    ($t:ident($reg:ty; $n:literal), compare: $wrap:path = $cmp:ident,
     splat: $set1:ident, load: $load:ident, store: $store:ident,
     abs: $andnot:ident, sqrt: $sqrt:ident, round: $round:ident,
     min: $min:ident, max: $max:ident) => {
        const LANES: usize = $n;
        type Array = [f64; $n];
        // SAFETY (both): the array and the register have the same size, and every bit pattern is
        // valid.
        const ZERO: Self = $t(unsafe { std::mem::transmute::<[f64; $n], $reg>([0.0; $n]) });
        const ONE: Self = $t(unsafe { std::mem::transmute::<[f64; $n], $reg>([1.0; $n]) });

        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: values of the type exist only on CPUs with its feature (its module's note).
            $t(unsafe { $set1(x) })
        }
        #[inline(always)]
        fn new(lanes: [f64; $n]) -> Self {
            // SAFETY: as in `splat`; the array holds the register's lanes.
            $t(unsafe { $load(lanes.as_ptr()) })
        }
        #[inline(always)]
        fn to_array(self) -> [f64; $n] {
            let mut lanes = [0.0; $n];
            // SAFETY: as in `splat`; the array holds the register's lanes.
            unsafe { $store(lanes.as_mut_ptr(), self.0) };
            lanes
        }
        register_lane_items!(@compare $wrap, $cmp, cmp_eq = _CMP_EQ_OQ);
        register_lane_items!(@compare $wrap, $cmp, cmp_ne = _CMP_NEQ_UQ);
        register_lane_items!(@compare $wrap, $cmp, cmp_lt = _CMP_LT_OQ);
        register_lane_items!(@compare $wrap, $cmp, cmp_le = _CMP_LE_OQ);
        register_lane_items!(@compare $wrap, $cmp, cmp_gt = _CMP_GT_OQ);
        register_lane_items!(@compare $wrap, $cmp, cmp_ge = _CMP_GE_OQ);
        #[inline(always)]
        fn abs(self) -> Self {
            // SAFETY: as in `splat`.
            $t(unsafe { $andnot(Self::splat(-0.0).0, self.0) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            // SAFETY: as in `splat`.
            $t(unsafe { $sqrt(self.0) })
        }
        #[inline(always)]
        fn round(self) -> Self {
            // SAFETY: as in `splat`.
            $t(unsafe { $round::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(self.0) })
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            // SAFETY: as in `splat`.
            $t(unsafe { $min(self.0, o.0) })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            // SAFETY: as in `splat`.
            $t(unsafe { $max(self.0, o.0) })
        }
    };
    (@compare $wrap:path, $cmp:ident, $method:ident = $predicate:ident) => {
        #[inline(always)]
        fn $method(self, o: Self) -> Self {
            // SAFETY: as in `splat`.
            $wrap(unsafe { $cmp::<$predicate>(self.0, o.0) })
        }
    };
}
pub(crate) use register_lane_items;
