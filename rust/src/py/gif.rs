//! Binding of the GIF frame encoder ([`crate::gif`]): the class `GifFrames`.
//!
//! Takes the colour table and each frame as `bytes`, or a frame as the Arrow C data interface
//! capsules of a Pillow image (`Image.__arrow_c_array__()`: the image's own memory, no copy),
//! encodes it with the GIL released (so the thread drawing the next frame runs meanwhile) and
//! returns its blocks as `bytes`. Size checks live in the kernel and come back as
//! `ValueError`.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyCapsule};

use super::arrow::arrow_pixels;
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

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<GifFrames>()?;
    Ok(())
}
