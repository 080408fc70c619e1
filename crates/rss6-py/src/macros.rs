//! `macro_rules!` shared by the binding modules: the per-function and per-class boilerplate of
//! wrappers that only convert arrays, call rss6 and convert back.

/// A `#[pyfunction]` whose array arguments are (6,) vectors (checked by `convert::vec6`, errors name
/// the argument), calling an rss6-core function that returns `rss6_core::Result` and converting its
/// value with `$out` (`out6` → `PyArray1` (6,), `out_mat6` → `PyArray2` (6, 6)):
///
/// `fn name(kp: &PyKinematicParams; pose, pose_dot) -> PyArray2 via out_mat6 = rss6_core::f(...)`.
///
/// A trailing `; g` adds the keyword-only gravity argument `g=None` (Python), bound to a `Vec3`
/// (m/s², base frame; default `rss6_core::GRAVITY`) for the call.
macro_rules! vec6_fn {
    (
        $(#[$doc:meta])*
        fn $name:ident($($p:ident: $pt:ty),* ; $($v:ident),+) -> $arr:ident via $out:ident = $call:expr
    ) => {
        $(#[$doc])*
        #[pyfunction]
        pub(crate) fn $name<'py>(
            py: Python<'py>,
            $($p: $pt,)*
            $($v: &Bound<'py, PyAny>,)+
        ) -> PyResult<Bound<'py, $arr<f64>>> {
            $(let $v = $crate::convert::vec6($v, stringify!($v))?;)+
            Ok($crate::convert::$out(py, &$call.map_err($crate::errors::core)?))
        }
    };
    (
        $(#[$doc:meta])*
        fn $name:ident($($p:ident: $pt:ty),* ; $($v:ident),+ ; $g:ident) -> $arr:ident via $out:ident = $call:expr
    ) => {
        $(#[$doc])*
        #[pyfunction]
        #[pyo3(signature = ($($p,)* $($v,)+ *, $g = None))]
        pub(crate) fn $name<'py>(
            py: Python<'py>,
            $($p: $pt,)*
            $($v: &Bound<'py, PyAny>,)+
            $g: Option<&Bound<'py, PyAny>>,
        ) -> PyResult<Bound<'py, $arr<f64>>> {
            $(let $v = $crate::convert::vec6($v, stringify!($v))?;)+
            let $g = $crate::dynamics::grav($g)?;
            Ok($crate::convert::$out(py, &$call.map_err($crate::errors::core)?))
        }
    };
}

/// The `#[pymethods]` of a controller wrapper whose `inner` has `fault()` and `reset()`: the given
/// methods, the `fault` getter and `reset` (documented by `$reset_doc`).
macro_rules! controller_methods {
    ($ty:ty, $reset_doc:literal, { $($methods:tt)* }) => {
        #[pymethods]
        impl $ty {
            $($methods)*

            /// The latched fault reason, or None.
            #[getter]
            fn fault(&self) -> Option<String> {
                $crate::ctrl::fault_text(self.inner.fault())
            }

            #[doc = $reset_doc]
            fn reset(&mut self) {
                self.inner.reset();
            }
        }
    };
}
