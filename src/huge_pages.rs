//! [`HugePageAlloc`]: a global allocator that backs large allocations (the
//! BVH's nodes and leaf blocks, the build's working arrays, meshes) with
//! 2 MiB pages where the operating system offers them.
//!
//! Why: a random ray through a big mesh touches a new page at almost every
//! node, and with 4 KiB pages the dragon's 55 MB tree spans 13,000 of them,
//! far more than the processor's TLB holds, so traversal waits on page
//! walks; building the tree also takes one page fault per 4 KiB written.
//! Linux's transparent huge pages are commonly enabled only for memory that
//! asks for them (`madvise`), which is what this allocator does: each large
//! block is its own 2 MiB-aligned mapping marked `MADV_HUGEPAGE` before its
//! first use. Where huge pages are unavailable the advice is ignored and the
//! memory is ordinary. Small allocations go to the system allocator.

use std::alloc::{GlobalAlloc, Layout, System};

/// Allocations of at least this many bytes get their own huge-page mapping:
/// rounding up to whole 2 MiB pages then leaves at most a fifth of the
/// mapping unused.
const LARGE: usize = 8 << 20;
const HUGE_PAGE: usize = 2 << 20;

/// The system allocator, with large blocks mapped on huge pages (see the
/// module documentation). Installed by the `tracer` binary with
/// `#[global_allocator]`.
pub struct HugePageAlloc;

fn is_large(layout: &Layout) -> bool {
    cfg!(target_os = "linux") && layout.size() >= LARGE && layout.align() <= HUGE_PAGE
}

fn mapped_size(size: usize) -> usize {
    size.div_ceil(HUGE_PAGE) * HUGE_PAGE
}

/// A fresh 2 MiB-aligned anonymous mapping of `size` bytes rounded up to
/// whole huge pages, advised to use them; null when the mapping fails.
#[cfg(target_os = "linux")]
fn map_large(size: usize) -> *mut u8 {
    let size = mapped_size(size);
    // Map one page more than needed and trim both ends to 2 MiB alignment:
    // a huge page can only back an aligned 2 MiB range.
    let span = size + HUGE_PAGE;
    // SAFETY: a new anonymous private mapping, overlapping nothing.
    let raw = unsafe {
        libc::mmap(
            std::ptr::null_mut(),
            span,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
            -1,
            0,
        )
    };
    if raw == libc::MAP_FAILED {
        return std::ptr::null_mut();
    }
    let start = raw as usize;
    let aligned = start.next_multiple_of(HUGE_PAGE);
    let head = aligned - start;
    let tail = span - head - size;
    // SAFETY: the head and tail are parts of the mapping just made that
    // nothing refers to, and the advice covers only the part kept; the
    // advice is only that (without huge pages the memory is still good).
    unsafe {
        if head > 0 {
            libc::munmap(raw, head);
        }
        if tail > 0 {
            libc::munmap((aligned + size) as *mut libc::c_void, tail);
        }
        libc::madvise(aligned as *mut libc::c_void, size, libc::MADV_HUGEPAGE);
    }
    aligned as *mut u8
}

#[cfg(not(target_os = "linux"))]
fn map_large(_size: usize) -> *mut u8 {
    unreachable!("large allocations are only mapped on Linux")
}

/// Unmaps a block from `map_large`.
///
/// # Safety
/// `ptr` came from `map_large(size)` and is not used again.
#[cfg(target_os = "linux")]
unsafe fn unmap_large(ptr: *mut u8, size: usize) {
    // SAFETY: by the caller's promise, exactly the pages `map_large` kept.
    unsafe { libc::munmap(ptr.cast(), mapped_size(size)) };
}

#[cfg(not(target_os = "linux"))]
unsafe fn unmap_large(_ptr: *mut u8, _size: usize) {
    unreachable!("large allocations are only mapped on Linux")
}

// SAFETY: large blocks are fresh mappings of at least the requested size,
// aligned to 2 MiB (at least the layout's alignment, which `is_large`
// checks), zero-filled by the kernel, and unmapped exactly once, by
// `dealloc` or `realloc`; everything else is the system allocator's, called
// with the caller's own promises.
unsafe impl GlobalAlloc for HugePageAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if is_large(&layout) {
            map_large(layout.size())
        } else {
            // SAFETY: the caller's promises about `layout`, passed on.
            unsafe { System.alloc(layout) }
        }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if is_large(&layout) {
            // Fresh anonymous mappings are zero already.
            map_large(layout.size())
        } else {
            // SAFETY: the caller's promises about `layout`, passed on.
            unsafe { System.alloc_zeroed(layout) }
        }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if is_large(&layout) {
            // SAFETY: a block of this layout is large, so it came from `map_large`.
            unsafe { unmap_large(ptr, layout.size()) }
        } else {
            // SAFETY: a block of this layout came from `System`.
            unsafe { System.dealloc(ptr, layout) }
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let Ok(new_layout) = Layout::from_size_align(new_size, layout.align()) else {
            return std::ptr::null_mut();
        };
        if !is_large(&layout) && !is_large(&new_layout) {
            // SAFETY: both sizes are small: the block is `System`'s and stays so.
            return unsafe { System.realloc(ptr, layout, new_size) };
        }
        if is_large(&layout)
            && is_large(&new_layout)
            && mapped_size(new_size) == mapped_size(layout.size())
        {
            // Still fits the pages already mapped, and unmaps the same ones.
            return ptr;
        }
        // SAFETY: `realloc`'s caller promises a non-zero `new_size`, so
        // `new_layout` is one `alloc` accepts.
        let new = unsafe { self.alloc(new_layout) };
        if !new.is_null() {
            // SAFETY: two distinct live blocks, each at least as long as
            // the bytes copied; the old one is freed once, with its layout.
            unsafe {
                std::ptr::copy_nonoverlapping(ptr, new, layout.size().min(new_size));
                self.dealloc(ptr, layout);
            }
        }
        new
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Blocks keep their bytes across every move between small and large,
    /// and large ones are aligned to huge pages.
    #[test]
    fn blocks_move_between_small_and_large_intact() {
        let alloc = HugePageAlloc;
        let sizes = [1000, LARGE + 5, LARGE + 6, 3 * LARGE, LARGE - 1, 64];
        let mut layout = Layout::from_size_align(sizes[0], 16).unwrap();
        // SAFETY: every block is used within its size and freed once.
        unsafe {
            let mut ptr = alloc.alloc(layout);
            assert!(!ptr.is_null());
            for i in 0..layout.size() {
                *ptr.add(i) = (i % 251) as u8;
            }
            let mut valid = layout.size();
            for &size in &sizes[1..] {
                ptr = alloc.realloc(ptr, layout, size);
                assert!(!ptr.is_null());
                layout = Layout::from_size_align(size, 16).unwrap();
                valid = valid.min(size);
                for i in 0..valid {
                    assert_eq!(*ptr.add(i), (i % 251) as u8, "byte {i} at size {size}");
                }
                for i in valid..size {
                    *ptr.add(i) = (i % 251) as u8;
                }
                valid = size;
                if is_large(&layout) {
                    assert_eq!(ptr as usize % HUGE_PAGE, 0);
                }
            }
            alloc.dealloc(ptr, layout);
            let zeroed = Layout::from_size_align(LARGE, 64).unwrap();
            let z = alloc.alloc_zeroed(zeroed);
            assert!((0..LARGE).step_by(4093).all(|i| *z.add(i) == 0));
            alloc.dealloc(z, zeroed);
        }
    }
}
