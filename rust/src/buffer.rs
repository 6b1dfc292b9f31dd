//! Large output buffers.
//!
//! A kernel that returns a new array of tens of megabytes spends a noticeable part of its time
//! in page faults (one per 4 KiB page the first time it is written). On Linux, buffers of at
//! least [`HUGE_MIN_BYTES`] are allocated zeroed (fresh memory from the kernel, not written
//! here) and advised as transparent huge pages, so the first touches fault once per 2 MiB.
//! Elsewhere, or if the advice is refused, this is an ordinary zeroed vector.

/// Buffers at least this large are advised as huge pages.
pub const HUGE_MIN_BYTES: usize = 4 << 20;

/// A zero-filled vector of `len` values, advised as transparent huge pages when large.
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
        }
    }
}
