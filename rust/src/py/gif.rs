//! Binding of the GIF frame encoder ([`crate::gif`]): the class `GifFrames`.
//!
//! Takes the colour table and each frame as `bytes`, or a frame as the Arrow C data interface
//! capsules of a Pillow image (`Image.__arrow_c_array__()`: the image's own memory, no copy),
//! encodes it with the GIL released (so the thread drawing the next frame runs meanwhile) and
//! returns its blocks as `bytes`. Size checks live in the kernel and come back as
//! `ValueError`.

use std::ffi::{c_char, c_void, CStr};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyCapsule, PyCapsuleMethods};

use crate::gif;

/// GIF89a frame blocks from RGB(X) frames of one size: palette lookup, changed rectangle, LZW.
///
/// ``GifFrames(width, height, lut)``: ``lut`` is 262,144 palette indices (``bytes``), the
/// index of colour ``(r, g, b)`` at ``(r >> 2) | (g >> 2) << 6 | (b >> 2) << 12``; index
/// ``TRANSPARENT`` (255) is reserved. ``frame(pixels, delay)`` encodes the next frame (packed
/// ``bytes``, RGB: ``width * height * 3``, or RGBX: ``* 4``, the fourth byte ignored; every
/// frame like the first) shown for ``delay`` centiseconds and returns
/// ``(blocks, (x0, y0, x1, y1))``: the graphic control extension, image descriptor and image
/// data of the frame, and the rectangle written (the whole first frame, then the pixels
/// that changed; unchanged ones inside are transparent over the kept previous frame).
/// The blocks use the file's global colour table.
#[pyclass(name = "GifFrames", module = "visprim._visprim")]
struct GifFrames {
    inner: gif::GifFrames,
}

#[pymethods]
impl GifFrames {
    #[classattr]
    const TRANSPARENT: u8 = gif::TRANSPARENT;

    #[new]
    fn new(width: usize, height: usize, lut: &[u8]) -> PyResult<Self> {
        Ok(Self {
            inner: gif::GifFrames::new(width, height, lut)?,
        })
    }

    /// As ``frame``, from the capsules ``(schema, array)`` of a Pillow RGB image's
    /// ``__arrow_c_array__()`` (one block of RGBX pixels, read in place).
    #[allow(clippy::type_complexity)]
    fn frame_arrow<'py>(
        &mut self,
        py: Python<'py>,
        schema: &Bound<'py, PyCapsule>,
        array: &Bound<'py, PyCapsule>,
        delay: u16,
    ) -> PyResult<(Bound<'py, PyBytes>, (usize, usize, usize, usize))> {
        let pixels = arrow_pixels(schema, array)?;
        self.frame(py, pixels, delay)
    }

    /// The blocks of the next frame and the rectangle written.
    #[allow(clippy::type_complexity)]
    fn frame<'py>(
        &mut self,
        py: Python<'py>,
        pixels: &[u8],
        delay: u16,
    ) -> PyResult<(Bound<'py, PyBytes>, (usize, usize, usize, usize))> {
        let inner = &mut self.inner;
        let (out, r) = py.detach(|| -> crate::Result<_> {
            let mut out = Vec::new();
            let r = inner.frame(pixels, delay, &mut out)?;
            Ok((out, r))
        })?;
        Ok((PyBytes::new(py, &out), (r.x0, r.y0, r.x1, r.y1)))
    }

    /// Bytes held by the encoder (colour table, two frames of indices, LZW buffers).
    #[getter]
    fn memory_bytes(&self) -> usize {
        self.inner.memory_bytes()
    }
}

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
fn arrow_pixels<'a>(
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

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<GifFrames>()?;
    Ok(())
}
