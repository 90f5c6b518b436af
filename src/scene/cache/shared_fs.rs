//! Whether a file lives on a filesystem that other machines write to
//! (NFS, SMB, FUSE mounts such as sshfs, cluster filesystems). There a
//! cache entry is read into memory rather than mapped: a mapped file that
//! another client truncates kills the reader with SIGBUS.

use std::path::Path;

/// Filesystem magic numbers (`statfs(2)`'s `f_type`) of shared filesystems.
const SHARED: [i64; 12] = [
    0x6969,      // NFS
    0x517B,      // SMB
    0xFF53_4D42, // CIFS
    0xFE53_4D42, // SMB2
    0x6573_5546, // FUSE (sshfs, s3fs, ...)
    0x0102_1997, // 9P
    0x00C3_6400, // Ceph
    0x5346_414F, // AFS
    0x0BD0_0BD0, // Lustre
    0x4750_4653, // GPFS
    0x0131_11A8, // IBRIX
    0xA501_FCF5, // VXFS
];

/// True when `path` is on a shared filesystem (or when that cannot be told:
/// copying is the safe choice). `TRACER_CACHE_COPY=1` forces copying and
/// `TRACER_CACHE_COPY=0` forces mapping, for filesystems this list misses.
pub fn is_shared(path: &Path) -> bool {
    match std::env::var("TRACER_CACHE_COPY").as_deref() {
        Ok("1") => return true,
        Ok("0") => return false,
        _ => {}
    }
    filesystem_type(path).is_none_or(|t| SHARED.contains(&t))
}

#[cfg(target_os = "linux")]
fn filesystem_type(path: &Path) -> Option<i64> {
    use std::os::unix::ffi::OsStrExt;
    let c_path = std::ffi::CString::new(path.as_os_str().as_bytes()).ok()?;
    let mut stats = std::mem::MaybeUninit::<libc::statfs>::uninit();
    // SAFETY: `c_path` is a valid NUL-terminated string and `stats` points
    // to writable memory of the right size for the call to fill.
    let result = unsafe { libc::statfs(c_path.as_ptr(), stats.as_mut_ptr()) };
    if result != 0 {
        return None;
    }
    // SAFETY: statfs returned 0, so it filled `stats`.
    let stats = unsafe { stats.assume_init() };
    #[allow(clippy::unnecessary_cast)] // f_type's width differs between targets.
    Some(stats.f_type as i64)
}

#[cfg(not(target_os = "linux"))]
fn filesystem_type(_: &Path) -> Option<i64> {
    // Unknown here: mapped files on local disks are the common case.
    Some(0)
}
