//! Sizes and allocation of buffers: checked, fallible, and fast for large outputs.
//!
//! Every size a kernel computes from its arguments goes through [`elements`] (checked
//! products) and every buffer whose size is not bounded by an input array goes through
//! [`try_zeroed_f64`] or [`try_filled`]: an impossible size or a failed allocation becomes
//! [`Error::Memory`] naming the sizes, never an overflow, an abort or a crash.
//!
//! A single buffer larger than the machine's physical memory ([`memory_limit`]) is refused up
//! front: with Linux's overcommit such an allocation may succeed and the process be killed
//! later, when the pages are touched.
//!
//! A kernel that returns a new array of tens of megabytes spends a noticeable part of its time
//! in page faults (one per 4 KiB page the first time it is written). On Linux, buffers of at
//! least [`HUGE_MIN_BYTES`] are allocated zeroed (fresh memory from the kernel, not written
//! here) and advised as transparent huge pages, so the first touches fault once per 2 MiB.
//! Elsewhere, or if the advice is refused, this is an ordinary zeroed vector.

use std::alloc::Layout;
use std::sync::OnceLock;

use crate::{Error, Result};

/// Buffers at least this large are advised as huge pages.
pub const HUGE_MIN_BYTES: usize = 4 << 20;

/// Bytes of physical memory of this machine (`isize::MAX` where unknown): the largest single
/// buffer a kernel attempts to allocate.
pub fn memory_limit() -> usize {
    static LIMIT: OnceLock<usize> = OnceLock::new();
    *LIMIT.get_or_init(|| physical_memory().unwrap_or(isize::MAX as usize))
}

#[cfg(target_os = "linux")]
fn physical_memory() -> Option<usize> {
    // SAFETY: sysconf only reads system information.
    let (pages, page) = unsafe {
        (
            libc::sysconf(libc::_SC_PHYS_PAGES),
            libc::sysconf(libc::_SC_PAGESIZE),
        )
    };
    if pages <= 0 || page <= 0 {
        return None;
    }
    (pages as usize).checked_mul(page as usize)
}

#[cfg(not(target_os = "linux"))]
fn physical_memory() -> Option<usize> {
    None
}

fn dims_str(dims: &[usize]) -> String {
    dims.iter()
        .map(|d| d.to_string())
        .collect::<Vec<_>>()
        .join(" x ")
}

/// The number of elements of `T` of a buffer of shape `dims`, checked: the product must not
/// overflow and the buffer must fit in memory ([`memory_limit`]). `what` names the buffer.
pub fn elements<T>(dims: &[usize], what: &str) -> Result<usize> {
    let too_large = |detail: String| {
        Error::Memory(format!(
            "{what} of {} {} values is too large: {detail}",
            dims_str(dims),
            std::any::type_name::<T>()
                .rsplit("::")
                .next()
                .unwrap_or("?")
        ))
    };
    let count = dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| too_large("the size overflows".into()))?;
    let bytes = count
        .checked_mul(std::mem::size_of::<T>())
        .filter(|&b| b <= isize::MAX as usize)
        .ok_or_else(|| too_large("more bytes than can be addressed".into()))?;
    check_bytes(bytes).map_err(|limit| {
        too_large(format!(
            "{} bytes, more than the {limit} bytes of memory of this machine",
            bytes
        ))
    })?;
    Ok(count)
}

/// `Err(limit)` if `bytes` exceed [`memory_limit`].
fn check_bytes(bytes: usize) -> std::result::Result<(), usize> {
    let limit = memory_limit();
    if bytes > limit {
        Err(limit)
    } else {
        Ok(())
    }
}

/// Checks that buffers of `bytes` bytes in total (e.g. a kernel's workspace) fit in memory.
pub fn check_total_bytes(bytes: Option<usize>, what: &str) -> Result<()> {
    match bytes {
        Some(b) if b <= isize::MAX as usize && check_bytes(b).is_ok() => Ok(()),
        Some(b) => Err(Error::Memory(format!(
            "{what} needs {b} bytes of memory, more than the {} bytes of this machine",
            memory_limit()
        ))),
        None => Err(Error::Memory(format!(
            "{what} needs more bytes of memory than can be addressed"
        ))),
    }
}

fn alloc_failed(what: &str, len: usize, elem: usize) -> Error {
    Error::Memory(format!(
        "cannot allocate {what}: {len} values ({} bytes)",
        len.saturating_mul(elem)
    ))
}

/// A zero-filled vector of `len` values, advised as transparent huge pages when large.
/// A failed allocation is [`Error::Memory`] (`what` names the buffer), never an abort.
pub fn try_zeroed_f64(len: usize, what: &str) -> Result<Vec<f64>> {
    let len = elements::<f64>(&[len], what)?;
    if len == 0 {
        return Ok(Vec::new());
    }
    let layout = Layout::array::<f64>(len).map_err(|_| alloc_failed(what, len, 8))?;
    // SAFETY: the layout has a non-zero size. A non-null result is a zeroed allocation of
    // exactly `len` f64 with the global allocator's layout for `Vec<f64>` of capacity `len`,
    // and all-zero bytes are the value 0.0, so the vector owns `len` initialised values.
    let v = unsafe {
        let p = std::alloc::alloc_zeroed(layout).cast::<f64>();
        if p.is_null() {
            return Err(alloc_failed(what, len, 8));
        }
        Vec::from_raw_parts(p, len, len)
    };
    #[cfg(target_os = "linux")]
    advise_huge(&v);
    Ok(v)
}

/// A vector of `len` copies of `value`; a failed allocation is [`Error::Memory`].
pub fn try_filled<T: Clone>(len: usize, value: T, what: &str) -> Result<Vec<T>> {
    let len = elements::<T>(&[len], what)?;
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| alloc_failed(what, len, std::mem::size_of::<T>()))?;
    v.resize(len, value);
    Ok(v)
}

/// An empty vector with room for `len` values; a failed allocation is [`Error::Memory`].
pub fn try_with_capacity<T>(len: usize, what: &str) -> Result<Vec<T>> {
    let len = elements::<T>(&[len], what)?;
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| alloc_failed(what, len, std::mem::size_of::<T>()))?;
    Ok(v)
}

/// A copy of `src`; a failed allocation is [`Error::Memory`].
pub fn try_copy<T: Clone>(src: &[T], what: &str) -> Result<Vec<T>> {
    let mut v = try_with_capacity(src.len(), what)?;
    v.extend_from_slice(src);
    Ok(v)
}

/// A zero-filled vector of `len` values (infallible form of [`try_zeroed_f64`], for sizes
/// bounded by an input array that already exists).
pub fn zeroed_f64(len: usize) -> Vec<f64> {
    let v = vec![0.0f64; len];
    #[cfg(target_os = "linux")]
    advise_huge(&v);
    v
}

#[cfg(target_os = "linux")]
fn advise_huge(v: &[f64]) {
    const PAGE: usize = 4096;
    let bytes = std::mem::size_of_val(v);
    if bytes < HUGE_MIN_BYTES {
        return;
    }
    let start = v.as_ptr() as usize;
    let aligned = start.next_multiple_of(PAGE);
    let end = (start + bytes) / PAGE * PAGE;
    if end > aligned {
        // SAFETY: the range lies inside the vector's own allocation; MADV_HUGEPAGE only changes
        // how the kernel backs these pages, never their contents. Failure is harmless.
        unsafe {
            libc::madvise(
                aligned as *mut libc::c_void,
                end - aligned,
                libc::MADV_HUGEPAGE,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeroed_of_any_size() {
        for len in [0usize, 1, 1000, HUGE_MIN_BYTES / 8 + 3] {
            let v = zeroed_f64(len);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 0.0));
            let w = try_zeroed_f64(len, "test buffer").unwrap();
            assert_eq!(w, v);
        }
    }

    #[test]
    fn sizes_are_checked() {
        assert_eq!(elements::<f64>(&[3, 4, 5], "x").unwrap(), 60);
        assert_eq!(elements::<f64>(&[], "x").unwrap(), 1);
        assert_eq!(elements::<f64>(&[0, usize::MAX], "x").unwrap(), 0);
        // Overflow of the product, of the bytes, and beyond physical memory.
        let err = elements::<f64>(&[1 << 40, 1 << 40], "out").unwrap_err();
        assert!(matches!(&err, Error::Memory(m) if m.contains("1099511627776 x 1099511627776")));
        assert!(matches!(
            elements::<f64>(&[1 << 61], "out"),
            Err(Error::Memory(_))
        ));
        assert!(matches!(
            elements::<u8>(&[isize::MAX as usize], "out"),
            Err(Error::Memory(_))
        ));
        let limit = memory_limit();
        assert!(elements::<u8>(&[limit], "out").is_ok());
        assert!(matches!(
            elements::<u8>(&[limit + 1], "out"),
            Err(Error::Memory(_))
        ));
        assert!(check_total_bytes(Some(10), "w").is_ok());
        assert!(check_total_bytes(None, "w").is_err());
        assert!(check_total_bytes(Some(limit + 1), "w").is_err());
    }

    #[test]
    fn impossible_allocations_are_errors() {
        assert!(matches!(
            try_zeroed_f64(usize::MAX, "big"),
            Err(Error::Memory(_))
        ));
        assert!(matches!(
            try_filled(1usize << 62, 0u32, "big"),
            Err(Error::Memory(_))
        ));
        assert!(matches!(
            try_with_capacity::<f64>(usize::MAX / 4, "big"),
            Err(Error::Memory(_))
        ));
        assert_eq!(try_filled(3, 7u8, "small").unwrap(), vec![7, 7, 7]);
        assert!(try_with_capacity::<u8>(5, "small").unwrap().capacity() >= 5);
    }
}
