//! Two legs in one pass: a pair of `f64` lanes that nalgebra's generic vectors accept, so a leg
//! recursion written once runs on two legs at a time (the compiler turns each lane-wise operation
//! into one SSE2 instruction on x86-64). Lane-wise IEEE arithmetic in the same order as the
//! scalar code: the results are the scalar ones bit for bit.

use core::ops::{Add, AddAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use nalgebra::SVector;

/// Two `f64` lanes.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub(super) struct Pair(wide::f64x2);

impl Pair {
    /// `[a, b]`.
    #[inline(always)]
    pub(super) fn new(a: f64, b: f64) -> Pair {
        Pair(wide::f64x2::new([a, b]))
    }

    /// Lane `k` (0 or 1).
    #[inline(always)]
    pub(super) fn get(self, k: usize) -> f64 {
        self.0.as_array_ref()[k & 1]
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt) => {
        impl $tr for Pair {
            type Output = Pair;
            #[inline(always)]
            fn $f(self, o: Pair) -> Pair {
                Pair(self.0 $op o.0)
            }
        }
        impl $tra for Pair {
            #[inline(always)]
            fn $fa(&mut self, o: Pair) {
                *self = *self $op o;
            }
        }
    };
}

lane_op!(Add, add, AddAssign, add_assign, +);
lane_op!(Sub, sub, SubAssign, sub_assign, -);
lane_op!(Mul, mul, MulAssign, mul_assign, *);

impl Neg for Pair {
    type Output = Pair;
    #[inline(always)]
    fn neg(self) -> Pair {
        Pair(-self.0)
    }
}

impl num_traits::Zero for Pair {
    #[inline(always)]
    fn zero() -> Pair {
        Pair(wide::f64x2::ZERO)
    }
    fn is_zero(&self) -> bool {
        self.0.as_array_ref() == &[0.0; 2]
    }
}

impl num_traits::One for Pair {
    #[inline(always)]
    fn one() -> Pair {
        Pair(wide::f64x2::ONE)
    }
}

impl From<f64> for Pair {
    /// The same value in both lanes.
    #[inline(always)]
    fn from(x: f64) -> Pair {
        Pair(wide::f64x2::splat(x))
    }
}

/// A value of one leg, and the same value of two legs side by side.
pub(super) trait Lanes: Copy {
    type Two;
    /// `a` in lane 0, `b` in lane 1.
    fn zip(a: &Self, b: &Self) -> Self::Two;
    /// The same value in both lanes.
    fn splat(&self) -> Self::Two;
}

impl Lanes for f64 {
    type Two = Pair;
    #[inline(always)]
    fn zip(a: &f64, b: &f64) -> Pair {
        Pair::new(*a, *b)
    }
    #[inline(always)]
    fn splat(&self) -> Pair {
        Pair::from(*self)
    }
}

impl<const N: usize> Lanes for SVector<f64, N> {
    type Two = SVector<Pair, N>;
    #[inline(always)]
    fn zip(a: &Self, b: &Self) -> Self::Two {
        SVector::from_fn(|r, _| Pair::new(a[r], b[r]))
    }
    #[inline(always)]
    fn splat(&self) -> Self::Two {
        self.map(Pair::from)
    }
}

/// Lane `k` (0 or 1) of a vector of pairs.
#[inline(always)]
pub(super) fn lane<const N: usize>(u: &SVector<Pair, N>, k: usize) -> SVector<f64, N> {
    u.map(|p| p.get(k))
}

/// What the leg recursions need of a lane type: `f64`, or [`Pair`].
pub(crate) trait Lane:
    nalgebra::Scalar
    + Copy
    + num_traits::Zero
    + Neg<Output = Self>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + From<f64>
{
}

impl<T> Lane for T where
    T: nalgebra::Scalar
        + Copy
        + num_traits::Zero
        + Neg<Output = T>
        + Add<Output = T>
        + Sub<Output = T>
        + Mul<Output = T>
        + AddAssign
        + SubAssign
        + MulAssign
        + From<f64>
{
}

/// [u]×, the matrix of u × · (nalgebra's `cross_matrix`, which wants a real field).
#[inline(always)]
pub(super) fn cross_matrix<T: Lane>(u: &nalgebra::Vector3<T>) -> nalgebra::Matrix3<T> {
    let z = T::zero();
    nalgebra::Matrix3::new(z, -u[2], u[1], u[2], z, -u[0], -u[1], u[0], z)
}
