//! Pixels of a Pillow image read in place through the Arrow C data interface
//! (`Image.__arrow_c_array__()`: two capsules holding the stable-ABI structs).

use std::ffi::{c_char, c_void, CStr};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyCapsule, PyCapsuleMethods};

/// The Arrow C data interface's schema and array structs (the stable ABI).
#[repr(C)]
struct ArrowSchema {
    format: *const c_char,
    name: *const c_char,
    metadata: *const c_char,
    flags: i64,
    n_children: i64,
    children: *mut *mut ArrowSchema,
    dictionary: *mut ArrowSchema,
    release: Option<unsafe extern "C" fn(*mut ArrowSchema)>,
    private_data: *mut c_void,
}

#[repr(C)]
struct ArrowArray {
    length: i64,
    null_count: i64,
    offset: i64,
    n_buffers: i64,
    n_children: i64,
    buffers: *mut *const c_void,
    children: *mut *mut ArrowArray,
    dictionary: *mut ArrowArray,
    release: Option<unsafe extern "C" fn(*mut ArrowArray)>,
    private_data: *mut c_void,
}

/// The pixel bytes of an exported Pillow image: a fixed-size list of 4 bytes per pixel
/// (format ``+w:4`` of ``C``), without nulls or offsets, one data buffer. The slice lives as
/// long as the capsules (their release callbacks run when they are collected).
pub(crate) fn arrow_pixels<'a>(
    schema: &'a Bound<'_, PyCapsule>,
    array: &'a Bound<'_, PyCapsule>,
) -> PyResult<&'a [u8]> {
    let bad =
        |what: &str| PyValueError::new_err(format!("not an image of 4 bytes a pixel: {what}"));
    let s = schema
        .pointer_checked(Some(c"arrow_schema"))?
        .cast::<ArrowSchema>();
    let a = array
        .pointer_checked(Some(c"arrow_array"))?
        .cast::<ArrowArray>();
    // SAFETY: the capsules hold live ArrowSchema / ArrowArray structs (checked by name; not
    // released until the capsules are collected, and they are borrowed for 'a). Every pointer
    // is checked for null and every count for range before it is followed.
    unsafe {
        let (s, a) = (s.as_ref(), a.as_ref());
        if s.release.is_none() || a.release.is_none() || s.format.is_null() {
            return Err(bad("released or empty capsules"));
        }
        if CStr::from_ptr(s.format).to_bytes() != b"+w:4" || s.n_children != 1 {
            return Err(bad("the schema is not +w:4"));
        }
        let child_schema = *s.children;
        if child_schema.is_null()
            || (*child_schema).format.is_null()
            || CStr::from_ptr((*child_schema).format).to_bytes() != b"C"
        {
            return Err(bad("the values are not uint8"));
        }
        if a.offset != 0 || a.null_count != 0 || a.n_children != 1 || a.children.is_null() {
            return Err(bad("offsets, nulls or children"));
        }
        let child = *a.children;
        if child.is_null() {
            return Err(bad("no child array"));
        }
        let c = &*child;
        if c.offset != 0 || c.null_count != 0 || c.n_buffers != 2 || c.buffers.is_null() {
            return Err(bad("the child array's offsets, nulls or buffers"));
        }
        let len = a
            .length
            .checked_mul(4)
            .filter(|&n| n == c.length && n >= 0)
            .ok_or_else(|| bad("lengths"))? as usize;
        let data = *c.buffers.add(1);
        if data.is_null() {
            return Err(bad("no data buffer"));
        }
        Ok(std::slice::from_raw_parts(data.cast::<u8>(), len))
    }
}
