//! Large read-mostly arrays (BVH nodes, triangle packs, instance leads) on 2 MiB pages.
//!
//! A ray through a large tree touches nodes and records scattered over tens of megabytes.
//! On 4 KiB pages most of those touches also miss the TLB (a few thousand entries, a few
//! megabytes), and a page walk is a second dependent memory access; a prefetch does not
//! hide it well. Linux backs memory with transparent huge pages (2 MiB) where a program
//! asks for them with `madvise(MADV_HUGEPAGE)`; with the policy of the development machine
//! (`/sys/kernel/mm/transparent_hugepage/enabled` set to `madvise`; other systems ship
//! `always`, which needs no asking) it grants them to no one else. Embree asks the same
//! for its large allocations. Measured in renderer/docs/performance.md ("Huge pages").
//!
//! The advice is a hint: it changes no value, only how the memory is mapped, and where
//! the system refuses it (another policy, another OS) nothing else changes. It is given
//! to a fresh allocation before the array is written, and pages the kernel maps from then
//! on are huge; but the allocator may hand out memory that freed arrays already touched
//! (glibc serves large blocks from its heap once large blocks have been freed), and those
//! pages stay small (on the 10⁶-triangle growth scene, 10 of the 16 MB of nodes became
//! huge). The advice also stays on such a heap range after the array is freed, so a later
//! allocation there may get huge pages too. A clone of an array is a plain allocation.

/// The size of a huge page on x86-64 and of the advice's alignment.
pub const HUGE_PAGE: usize = 2 << 20;

/// Arrays of at least this many bytes are put on huge pages: any range this long holds
/// a whole aligned huge page, whatever its start (the allocator's blocks are not aligned
/// to 2 MiB, and only whole aligned pages inside the block can be huge).
pub const HUGE_ABOVE: usize = 2 * HUGE_PAGE;

/// `v`'s items in a new allocation advised for huge pages when they take at least
/// [`HUGE_ABOVE`] bytes (on Linux); otherwise `v` itself. The copy briefly doubles the
/// array's memory.
pub fn on_huge_pages<T: Copy>(v: Vec<T>) -> Vec<T> {
    if !cfg!(target_os = "linux") || std::mem::size_of_val(v.as_slice()) < HUGE_ABOVE {
        return v;
    }
    let mut out = Vec::with_capacity(v.len());
    advise(out.as_mut_ptr(), v.len());
    out.extend_from_slice(&v);
    out
}

/// An empty vector with room for `n` items, whose memory the kernel is asked to map on
/// huge pages when it takes at least [`HUGE_ABOVE`] bytes. Fill it without growing it
/// past `n` (a reallocation would lose the advice).
pub fn huge_with_capacity<T>(n: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    if n.saturating_mul(std::mem::size_of::<T>()) >= HUGE_ABOVE {
        advise(v.as_mut_ptr(), n);
    }
    v
}

/// The whole aligned huge pages inside the `bytes` bytes at address `start`, as the
/// address of the first and their length in bytes, when there is one.
fn whole_pages(start: usize, bytes: usize) -> Option<(usize, usize)> {
    let first = start.next_multiple_of(HUGE_PAGE);
    let last = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
    (first < last).then(|| (first, last - first))
}

/// Advises the whole huge pages inside the `n` items at `p` (an allocation of at least
/// `n` items).
#[cfg(target_os = "linux")]
fn advise<T>(p: *mut T, n: usize) {
    if let Some((first, len)) = whole_pages(p as usize, n * std::mem::size_of::<T>()) {
        // SAFETY: `[first, first + len)` lies inside the allocation of `n` items at `p`, which
        // this process owns (`whole_pages` gives only pages inside its range: unit
        // tested); MADV_HUGEPAGE changes only how those pages are mapped, never their
        // contents, and a refusal (an error return) is harmless and ignored.
        unsafe {
            libc::madvise(first as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
        }
    }
}

/// Elsewhere there is no such advice; the memory stays as the allocator gave it.
#[cfg(not(target_os = "linux"))]
fn advise<T>(_p: *mut T, _n: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `VmFlags` of the mapping of this process that holds `addr` (Linux's
    /// /proc/self/smaps: `hg` marks memory advised with MADV_HUGEPAGE).
    #[cfg(target_os = "linux")]
    fn vm_flags(addr: usize) -> String {
        let smaps = std::fs::read_to_string("/proc/self/smaps").expect("/proc/self/smaps");
        let mut inside = false;
        for line in smaps.lines() {
            if let Some((range, _)) = line.split_once(' ') {
                if let Some((a, b)) = range.split_once('-') {
                    if let (Ok(a), Ok(b)) =
                        (usize::from_str_radix(a, 16), usize::from_str_radix(b, 16))
                    {
                        inside = (a..b).contains(&addr);
                        continue;
                    }
                }
            }
            if inside {
                if let Some(flags) = line.strip_prefix("VmFlags:") {
                    return flags.trim().to_string();
                }
            }
        }
        panic!(
            "no mapping with a VmFlags line holds {addr:#x} in /proc/self/smaps (an older \
         kernel prints no VmFlags: then this test cannot see the advice)"
        )
    }

    /// Fails, naming `what`, unless the first and the last of the whole huge pages
    /// inside the `bytes` at `p` carry `hg` (the advice). A kernel built without
    /// transparent huge pages refuses the advice (and has no such directory): then there
    /// is nothing to see.
    #[cfg(target_os = "linux")]
    fn assert_advised<T>(p: *const T, bytes: usize, what: &str) {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage").exists() {
            return;
        }
        let (first, len) = whole_pages(p as usize, bytes)
            .unwrap_or_else(|| panic!("no whole huge page inside {bytes} bytes at {p:?}"));
        for addr in [first, first + len - 1] {
            let flags = vm_flags(addr);
            assert!(
                flags.split(' ').any(|x| x == "hg"),
                "{what} of {bytes} bytes was not advised for huge pages, from its first whole \
                 huge page to its last (pages::advise); VmFlags at {addr:#x}: {flags:?}"
            );
        }
    }

    #[test]
    fn large_arrays_keep_their_items_and_are_advised() {
        let n = HUGE_ABOVE / 8 + 1000;
        let v: Vec<u64> = (0..n as u64).map(|k| k * 7 + 1).collect();
        let moved = on_huge_pages(v.clone());
        assert_eq!(moved, v, "on_huge_pages must copy every item in order");
        #[cfg(target_os = "linux")]
        {
            assert_advised(moved.as_ptr(), n * 8, "on_huge_pages' copy");
            let empty: Vec<u64> = huge_with_capacity(n);
            assert_advised(empty.as_ptr(), n * 8, "huge_with_capacity's room");
        }
    }

    /// `whole_pages` gives exactly the aligned 2 MiB pages that lie wholly inside the
    /// range (start and length): none outside it, none of those inside left out.
    #[test]
    fn whole_pages_are_those_inside_the_range() {
        let h = HUGE_PAGE;
        for (start, bytes, want) in [
            (0, 2 * h, Some((0, 2 * h))),
            (16, 2 * h, Some((h, h))),
            (16, 3 * h, Some((h, 2 * h))),
            (h - 1, h, None),
            (h - 1, h + 1, Some((h, h))),
            (5 * h + 4096, 3 * h - 4096, Some((6 * h, 2 * h))),
            (5 * h + 4096, 3 * h - 4097, Some((6 * h, h))),
            (7 * h, 0, None),
        ] {
            assert_eq!(
                whole_pages(start, bytes),
                want,
                "whole huge pages inside {bytes} bytes at {start:#x} (pages::whole_pages)"
            );
        }
    }

    #[test]
    fn small_arrays_stay_where_they_are() {
        let v: Vec<u64> = (0..(HUGE_ABOVE / 8 - 1) as u64).collect();
        let p = v.as_ptr();
        let kept = on_huge_pages(v);
        assert_eq!(
            kept.as_ptr(),
            p,
            "an array under HUGE_ABOVE bytes was copied (pages::on_huge_pages)"
        );
        // From HUGE_ABOVE bytes on, an array moves (into advised memory), on Linux.
        if !cfg!(target_os = "linux") {
            return;
        }
        let v: Vec<u64> = (0..(HUGE_ABOVE / 8) as u64).collect();
        let p = v.as_ptr();
        let moved = on_huge_pages(v);
        assert_ne!(
            moved.as_ptr(),
            p,
            "an array of HUGE_ABOVE bytes was left where it was (pages::on_huge_pages)"
        );
    }

    /// `huge_with_capacity` advises from [`HUGE_ABOVE`] bytes on. (Not checked below it:
    /// memory there may be advised already, as a range that an earlier array of this
    /// process advised and gave back.)
    #[cfg(target_os = "linux")]
    #[test]
    fn room_for_large_arrays_is_advised() {
        let v: Vec<u8> = huge_with_capacity(HUGE_ABOVE);
        assert_advised(
            v.as_ptr(),
            HUGE_ABOVE,
            "huge_with_capacity's room of HUGE_ABOVE",
        );
    }
}
