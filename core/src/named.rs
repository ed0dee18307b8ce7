//! Lookups in the tables of named settings (`NAMED` of
//! [`PipelineParams`](crate::pipeline::PipelineParams) and
//! [`C2fParams`](crate::stereo::c2f::C2fParams)): operating points have
//! names, and a name maps to one setting and back.

/// The setting called `name` in `named`.
pub(crate) fn by_name<T: Copy>(named: &[(&'static str, T)], name: &str) -> Option<T> {
    named.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
}

/// The name of `value` in `named`, if it is one of the settings.
pub(crate) fn name_of<T: PartialEq>(
    named: &[(&'static str, T)],
    value: &T,
) -> Option<&'static str> {
    named.iter().find(|(_, v)| v == value).map(|&(n, _)| n)
}
