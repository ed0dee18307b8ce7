//! Per-pixel values that may be OFF, the paper's "discarded data" state.
//!
//! [`MaybeOff<T>`] stores OFF as one reserved value of `T` (its *niche*, see
//! [`OffValue`]), so an OFF-capable map is a plain `[MaybeOff<T>]` of the same
//! size as `[T]`: no flag plane, no second allocation. A map is just an
//! [`ImageView`](crate::image::ImageView) of `MaybeOff<T>`.
//!
//! ```
//! use protogist::off::MaybeOff;
//! let on = MaybeOff::on(12u16).unwrap();
//! assert_eq!(on.get(), Some(12));
//! assert_eq!(MaybeOff::<u16>::OFF.get(), None);
//! // The reserved value itself cannot be stored as ON.
//! assert!(MaybeOff::on(u16::MAX).is_none());
//! assert_eq!(core::mem::size_of::<MaybeOff<u16>>(), 2);
//! ```

/// A type with one value reserved to mean OFF.
pub trait OffValue: Copy + Eq + bytemuck::Pod {
    /// The reserved value.
    const OFF: Self;
}

impl OffValue for u8 {
    const OFF: Self = u8::MAX;
}
impl OffValue for u16 {
    const OFF: Self = u16::MAX;
}
impl OffValue for i16 {
    const OFF: Self = i16::MIN;
}
impl OffValue for u32 {
    const OFF: Self = u32::MAX;
}
impl OffValue for i32 {
    const OFF: Self = i32::MIN;
}

/// A value or OFF, in the space of one `T`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
pub struct MaybeOff<T>(T);

impl<T: OffValue> MaybeOff<T> {
    /// The OFF state.
    pub const OFF: Self = Self(T::OFF);

    /// An ON value, or `None` if `value` is the reserved OFF value.
    pub fn on(value: T) -> Option<Self> {
        if value == T::OFF {
            None
        } else {
            Some(Self(value))
        }
    }

    /// `value` if it is not the reserved value, else OFF.
    pub fn from_raw(value: T) -> Self {
        Self(value)
    }

    /// The value, or `None` when OFF.
    pub fn get(self) -> Option<T> {
        if self.is_off() {
            None
        } else {
            Some(self.0)
        }
    }

    /// True when OFF.
    pub fn is_off(self) -> bool {
        self.0 == T::OFF
    }

    /// True when ON.
    pub fn is_on(self) -> bool {
        !self.is_off()
    }

    /// The stored value, with OFF as `T::OFF`.
    pub fn raw(self) -> T {
        self.0
    }
}

impl<T: OffValue> Default for MaybeOff<T> {
    /// OFF.
    fn default() -> Self {
        Self::OFF
    }
}

impl<T: OffValue> From<Option<T>> for MaybeOff<T> {
    fn from(v: Option<T>) -> Self {
        v.map_or(Self::OFF, Self)
    }
}
