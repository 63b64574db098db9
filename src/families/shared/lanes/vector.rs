//! What the lanes need of an f64 vector, as one trait: the arithmetic, comparisons that return
//! all-ones masks, `blend` and a bit shift ([`super::functions`] builds exp, sin/cos, asin and
//! acos on them, as the methods of its `LaneFunctions`). It is implemented by `wide::f64x4` (any
//! x86-64; the default target builds it as two SSE2 halves), on CPUs with AVX2 by
//! [`super::avx2::F64x4`], one 256-bit register (run as a [`Pair`] of them), and on CPUs with
//! AVX-512 by [`super::avx512::F64x8`], eight lanes in one 512-bit register (their operators and
//! one-intrinsic methods come from [`super::register`]'s macros). All do the same IEEE
//! operations lane by lane, so they give the same bits.

use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

use wide::{f64x4, u64x4, CmpEq, CmpGe, CmpGt, CmpLe, CmpLt, CmpNe};

/// The most lanes any [`Lane`] type has.
pub(crate) const MAX_LANES: usize = 8;

/// `LANES` f64 lanes; masks are vectors whose set lanes have every bit set.
pub(crate) trait Lane:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + Not<Output = Self>
{
    /// How many samples one vector holds (at most [`MAX_LANES`]).
    const LANES: usize;
    /// `[f64; LANES]`.
    type Array: Copy + Default + AsRef<[f64]> + AsMut<[f64]>;
    const ZERO: Self;
    const ONE: Self;
    fn splat(x: f64) -> Self;
    fn new(lanes: Self::Array) -> Self;
    fn to_array(self) -> Self::Array;
    /// The sign bits, lane 0 lowest.
    fn move_mask(self) -> i32;
    /// `self`'s set lanes take `t`, the others `f`.
    fn blend(self, t: Self, f: Self) -> Self;
    fn cmp_eq(self, o: Self) -> Self;
    /// Not equal, or unordered.
    fn cmp_ne(self, o: Self) -> Self;
    fn cmp_lt(self, o: Self) -> Self;
    fn cmp_le(self, o: Self) -> Self;
    fn cmp_gt(self, o: Self) -> Self;
    fn cmp_ge(self, o: Self) -> Self;
    fn abs(self) -> Self;
    fn sqrt(self) -> Self;
    /// To the nearest integer.
    fn round(self) -> Self;
    /// `o` must not be NaN: where `self` is, both kernels give `o`.
    fn min(self, o: Self) -> Self;
    /// As `min`.
    fn max(self, o: Self) -> Self;
    /// `self`'s magnitude with `sign`'s sign.
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        self.abs() | (sign & Self::splat(-0.0))
    }
    /// False for NaN too (an unordered comparison).
    #[inline(always)]
    fn is_finite(self) -> Self {
        self.abs().cmp_lt(Self::splat(f64::INFINITY))
    }
    /// Each lane's bits shifted left by `N`.
    fn shl_bits<const N: i32>(self) -> Self;

    /// Lane `l` is `f(l)`.
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        let mut lanes = Self::Array::default();
        for (l, x) in lanes.as_mut().iter_mut().enumerate() {
            *x = f(l);
        }
        Self::new(lanes)
    }
    /// [`Lane::move_mask`] with every lane set.
    #[inline(always)]
    fn all_bits() -> u32 {
        (1u32 << Self::LANES) - 1
    }

    /// `self · b + c`, not fused: a fused multiply-add would round differently on the CPUs that
    /// have one.
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        self * b + c
    }
}

/// `fn $name(self, …) -> $out` of [`Lane`] as wide's function of the same name.
macro_rules! delegate {
    ($($name:ident($($arg:ident),*) -> $out:ty = $to:path;)*) => {
        $(
            #[inline(always)]
            fn $name(self $(, $arg: Self)*) -> $out {
                $to(self $(, $arg)*)
            }
        )*
    };
}

/// wide's own methods (not its transcendental functions: the lanes' own are as fast on SSE2 and
/// give the AVX2 kernel's bits).
impl Lane for f64x4 {
    const LANES: usize = 4;
    type Array = [f64; 4];
    const ZERO: Self = f64x4::ZERO;
    const ONE: Self = f64x4::ONE;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        f64x4::splat(x)
    }
    #[inline(always)]
    fn new(lanes: [f64; 4]) -> Self {
        f64x4::new(lanes)
    }
    delegate! {
        to_array() -> [f64; 4] = f64x4::to_array;
        move_mask() -> i32 = f64x4::move_mask;
        blend(t, f) -> Self = f64x4::blend;
        cmp_eq(o) -> Self = CmpEq::cmp_eq;
        cmp_ne(o) -> Self = CmpNe::cmp_ne;
        cmp_lt(o) -> Self = CmpLt::cmp_lt;
        cmp_le(o) -> Self = CmpLe::cmp_le;
        cmp_gt(o) -> Self = CmpGt::cmp_gt;
        cmp_ge(o) -> Self = CmpGe::cmp_ge;
        abs() -> Self = f64x4::abs;
        sqrt() -> Self = f64x4::sqrt;
        round() -> Self = f64x4::round;
        min(o) -> Self = f64x4::min;
        max(o) -> Self = f64x4::max;
        copysign(sign) -> Self = f64x4::copysign;
        is_finite() -> Self = f64x4::is_finite;
    }
    #[inline(always)]
    fn shl_bits<const N: i32>(self) -> Self {
        let bits: u64x4 = bytemuck::cast(self);
        bytemuck::cast(bits << N)
    }
}

/// Two vectors side by side as one of twice the lanes: the same operations on each half, so
/// the same bits as the halves alone; two independent chains of work for the CPU to overlap.
#[derive(Clone, Copy)]
pub(crate) struct Pair<V>(V, V);

macro_rules! pair_binary {
    ($trait:ident, $method:ident) => {
        impl<V: Lane> $trait for Pair<V> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Pair(self.0.$method(o.0), self.1.$method(o.1))
            }
        }
    };
}

macro_rules! pair_scalar {
    ($trait:ident, $method:ident) => {
        impl<V: Lane> $trait<f64> for Pair<V> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: f64) -> Self {
                Pair(self.0.$method(o), self.1.$method(o))
            }
        }
    };
}
pair_binary!(Add, add);
pair_binary!(Sub, sub);
pair_binary!(Mul, mul);
pair_binary!(Div, div);
pair_binary!(BitAnd, bitand);
pair_binary!(BitOr, bitor);
pair_binary!(BitXor, bitxor);
pair_scalar!(Add, add);
pair_scalar!(Sub, sub);
pair_scalar!(Mul, mul);
pair_scalar!(Div, div);

impl<V: Lane> Neg for Pair<V> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Pair(-self.0, -self.1)
    }
}

impl<V: Lane> Not for Pair<V> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Pair(!self.0, !self.1)
    }
}

macro_rules! pair_each {
    ($($name:ident($($arg:ident),*);)*) => {
        $(
            #[inline(always)]
            fn $name(self $(, $arg: Self)*) -> Self {
                Pair(self.0.$name($($arg.0),*), self.1.$name($($arg.1),*))
            }
        )*
    };
}

impl<V: Lane<Array = [f64; 4]>> Lane for Pair<V> {
    const LANES: usize = 8;
    type Array = [f64; 8];
    const ZERO: Self = Pair(V::ZERO, V::ZERO);
    const ONE: Self = Pair(V::ONE, V::ONE);
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Pair(V::splat(x), V::splat(x))
    }
    #[inline(always)]
    fn new(lanes: [f64; 8]) -> Self {
        let [a, b, c, d, e, f, g, h] = lanes;
        Pair(V::new([a, b, c, d]), V::new([e, f, g, h]))
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 8] {
        let ([a, b, c, d], [e, f, g, h]) = (self.0.to_array(), self.1.to_array());
        [a, b, c, d, e, f, g, h]
    }
    #[inline(always)]
    fn move_mask(self) -> i32 {
        self.0.move_mask() | (self.1.move_mask() << V::LANES)
    }
    #[inline(always)]
    fn blend(self, t: Self, f: Self) -> Self {
        Pair(self.0.blend(t.0, f.0), self.1.blend(t.1, f.1))
    }
    pair_each! {
        cmp_eq(o);
        cmp_ne(o);
        cmp_lt(o);
        cmp_le(o);
        cmp_gt(o);
        cmp_ge(o);
        abs();
        sqrt();
        round();
        min(o);
        max(o);
        copysign(sign);
        is_finite();
    }
    #[inline(always)]
    fn shl_bits<const N: i32>(self) -> Self {
        Pair(self.0.shl_bits::<N>(), self.1.shl_bits::<N>())
    }
}
