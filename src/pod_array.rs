//! [`PodArray`]: an array of plain records that is either an ordinary
//! vector or a section of a read-only memory-mapped file. The scene cache
//! maps its entries instead of copying them: on a warm load the triangles,
//! shading records and BVH are used where the page cache already holds
//! them (measured: the dragon's 136 MiB entry loads in about a third of the time a copy
//! into fresh vectors takes, whose page faults cost more than the copy).

use bytemuck::Pod;
use std::ops::{Deref, DerefMut};
use std::sync::Arc;

/// A slice of plain records owned either as a vector or as part of a shared
/// read-only file map; it derefs to `[T]`. Writing to a mapped array first
/// copies it into a vector.
pub struct PodArray<T: Pod> {
    /// Points into `owner`; cached so that indexing costs what a `Vec`'s
    /// does. Taken once, mutably, from the vector, and the only way its
    /// records are reached afterwards.
    ptr: *mut T,
    len: usize,
    owner: Owner<T>,
}

enum Owner<T> {
    Vec(Vec<T>),
    Map(Arc<memmap2::Mmap>),
}

// SAFETY: a `PodArray` owns its data (a vector, or a shared read-only map
// that lives as long as any array pointing into it); the pointer is only
// read through `&self`, and writing goes through `DerefMut`, which first
// turns a mapped array into an owned vector.
unsafe impl<T: Pod + Send> Send for PodArray<T> {}
// SAFETY: as for `Send`: shared access only reads, and the data it reads is
// never changed while shared.
unsafe impl<T: Pod + Sync> Sync for PodArray<T> {}

impl<T: Pod> PodArray<T> {
    /// `len` records of `T` at byte `offset` of `map`. `None` when the
    /// range lies outside the map or `offset` is not aligned for `T`.
    pub fn from_map(map: &Arc<memmap2::Mmap>, offset: usize, len: usize) -> Option<PodArray<T>> {
        let bytes = len.checked_mul(std::mem::size_of::<T>())?;
        let end = offset.checked_add(bytes)?;
        let section = map.get(offset..end)?;
        let records: &[T] = bytemuck::try_cast_slice(section).ok()?;
        Some(PodArray {
            // Only ever read: `deref_mut` copies a mapped array first.
            ptr: records.as_ptr().cast_mut(),
            len,
            owner: Owner::Map(map.clone()),
        })
    }

    /// Whether the records live in a file map rather than a vector.
    pub fn is_mapped(&self) -> bool {
        matches!(self.owner, Owner::Map(_))
    }

    /// The records as a vector: the owned one, or a copy of the mapped ones.
    pub fn into_vec(self) -> Vec<T> {
        match self.owner {
            Owner::Vec(v) => v,
            Owner::Map(_) => self.deref().to_vec(),
        }
    }
}

impl<T: Pod> From<Vec<T>> for PodArray<T> {
    fn from(mut v: Vec<T>) -> Self {
        PodArray {
            ptr: v.as_mut_ptr(),
            len: v.len(),
            owner: Owner::Vec(v),
        }
    }
}

impl<T: Pod> Default for PodArray<T> {
    fn default() -> Self {
        Vec::new().into()
    }
}

impl<T: Pod> Deref for PodArray<T> {
    type Target = [T];

    #[inline(always)]
    fn deref(&self) -> &[T] {
        // SAFETY: `ptr` and `len` describe records inside `owner`, which
        // this array keeps alive and never reallocates.
        unsafe { std::slice::from_raw_parts(self.ptr, self.len) }
    }
}

impl<T: Pod> DerefMut for PodArray<T> {
    /// A mapped array is copied into a vector first (copy on write).
    fn deref_mut(&mut self) -> &mut [T] {
        if let Owner::Map(_) = self.owner {
            *self = PodArray::from(self.deref().to_vec());
        }
        // SAFETY: the array now owns its vector, which `ptr` was taken from
        // mutably and which is never touched through `owner` again.
        unsafe { std::slice::from_raw_parts_mut(self.ptr, self.len) }
    }
}

impl<T: Pod> Clone for PodArray<T> {
    fn clone(&self) -> Self {
        match &self.owner {
            Owner::Vec(v) => PodArray::from(v.clone()),
            Owner::Map(m) => PodArray {
                ptr: self.ptr,
                len: self.len,
                owner: Owner::Map(m.clone()),
            },
        }
    }
}

impl<T: Pod + std::fmt::Debug> std::fmt::Debug for PodArray<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<'a, T: Pod> IntoIterator for &'a PodArray<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}
