//! One cache entry on disk: a fixed header, a table of sections, and the
//! sections themselves, each a plain array of fixed-layout records.
//!
//! ```text
//! offset  size  field
//!      0     8  magic "TRCACHE\0"
//!      8     4  format version (little-endian u32)
//!     12     4  section count
//!     16    32  key (BLAKE3 of everything that determines the geometry)
//!     48     8  payload length: bytes after the header and the table
//!     56    32  checksum: BLAKE3 of every byte after the header
//!     88     8  reserved, zero
//!     96        section table: per section kind u32, record size u32, length u64
//!               then the sections in table order, each starting on a
//!               multiple of 64 bytes (zero padding between them)
//! ```
//!
//! Loading maps the file and uses each section in place as an array of its
//! record type: no copy, no parsing. Every length is checked against the
//! file's size and every record size and alignment against the type before
//! a section is used, and the checksum over every byte after the header, so a
//! truncated, corrupt, foreign or older entry is refused, not trusted.

use crate::pod_array::PodArray;
use bytemuck::Pod;
use std::io::Write;
use std::sync::Arc;

/// The first eight bytes of every entry.
pub const MAGIC: [u8; 8] = *b"TRCACHE\0";
/// Bump whenever the layout of any section or of the metadata changes.
pub const FORMAT_VERSION: u32 = 2;
/// Size of the fixed header, before the section table.
pub const HEADER_BYTES: usize = 96;
const TABLE_ROW_BYTES: usize = 16;
/// Sections start on multiples of this, enough for any record type's alignment.
pub const SECTION_ALIGN: usize = 64;
/// More sections than any version writes: a count beyond this is corruption.
const MAX_SECTIONS: u32 = 16;

/// Why an entry was refused.
#[derive(Debug, thiserror::Error)]
pub enum Invalid {
    /// The file does not start with [`MAGIC`].
    #[error("not a cache entry (bad magic bytes)")]
    Magic,
    /// Written by another cache format version: the one named.
    #[error("written by cache format {0}, this build reads format {FORMAT_VERSION}")]
    Version(u32),
    /// The key in the header is not the one the file name says.
    #[error("its key does not match its file name")]
    Key,
    /// Lengths disagree with each other or with the file's size (the message says which).
    #[error("truncated or oversized: {0}")]
    Length(String),
    /// The bytes after the header do not match the checksum.
    #[error("checksum mismatch: the payload is corrupt")]
    Checksum,
    /// Inconsistent in another way, e.g. non-zero reserved bytes, a missing
    /// section or a wrong record size (the message says what).
    #[error("malformed: {0}")]
    Malformed(String),
    /// The file could not be read.
    #[error("cannot be read: {0}")]
    Io(#[from] std::io::Error),
}

/// One row of the section table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SectionInfo {
    /// What the section holds (a kind number the entry's reader expects in order).
    pub kind: u32,
    /// Size of one record, in bytes, checked against the record type.
    pub record_bytes: u32,
    /// Length of the section, in bytes (a multiple of `record_bytes`).
    pub length: u64,
}

/// An entry's header and section table, as read and checked.
pub struct Header {
    /// The cache key the entry was stored under.
    pub key: [u8; 32],
    /// Bytes after the header and the table: every section with its padding.
    pub payload_length: u64,
    /// BLAKE3 of every byte after the header.
    pub checksum: [u8; 32],
    /// The section table, in file order.
    pub sections: Vec<SectionInfo>,
    /// Where each section starts in the file.
    pub offsets: Vec<u64>,
}

impl Header {
    fn table_bytes(sections: &[SectionInfo]) -> Vec<u8> {
        let mut t = Vec::with_capacity(sections.len() * TABLE_ROW_BYTES);
        for s in sections {
            t.extend_from_slice(&s.kind.to_le_bytes());
            t.extend_from_slice(&s.record_bytes.to_le_bytes());
            t.extend_from_slice(&s.length.to_le_bytes());
        }
        t
    }
}

/// A section to write: its kind and its bytes.
pub struct Section<'a> {
    /// What the section holds (checked when it is read back).
    pub kind: u32,
    /// Size of one record, in bytes.
    pub record_bytes: u32,
    /// The records, as bytes.
    pub bytes: &'a [u8],
}

impl<'a> Section<'a> {
    /// The section of `kind` holding `records`, as bytes.
    pub fn of<T: Pod>(kind: u32, records: &'a [T]) -> Section<'a> {
        Section {
            kind,
            record_bytes: std::mem::size_of::<T>() as u32,
            bytes: bytemuck::cast_slice(records),
        }
    }
}

/// Writes a whole entry to `out`.
pub fn write(out: &mut impl Write, key: &[u8; 32], sections: &[Section]) -> std::io::Result<()> {
    let infos: Vec<SectionInfo> = sections
        .iter()
        .map(|s| SectionInfo {
            kind: s.kind,
            record_bytes: s.record_bytes,
            length: s.bytes.len() as u64,
        })
        .collect();
    let table = Header::table_bytes(&infos);
    let (offsets, end) = section_offsets(&infos).expect("in-memory sections fit in u64");
    let table_end = (HEADER_BYTES + table.len()) as u64;
    let padding = |at: u64, offset: u64| &[0u8; SECTION_ALIGN][..(offset - at) as usize];
    let mut hasher = blake3::Hasher::new();
    hasher.update(&table);
    let mut at = table_end;
    for (s, &offset) in sections.iter().zip(&offsets) {
        hasher.update(padding(at, offset));
        hash(&mut hasher, s.bytes);
        at = offset + s.bytes.len() as u64;
    }
    let mut header = [0u8; HEADER_BYTES];
    header[0..8].copy_from_slice(&MAGIC);
    header[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
    header[12..16].copy_from_slice(&(sections.len() as u32).to_le_bytes());
    header[16..48].copy_from_slice(key);
    header[48..56].copy_from_slice(&(end - table_end).to_le_bytes());
    header[56..88].copy_from_slice(hasher.finalize().as_bytes());
    out.write_all(&header)?;
    out.write_all(&table)?;
    let mut at = table_end;
    for (s, &offset) in sections.iter().zip(&offsets) {
        out.write_all(padding(at, offset))?;
        out.write_all(s.bytes)?;
        at = offset + s.bytes.len() as u64;
    }
    Ok(())
}

/// Large sections hash on every core: the checksum must not cost more than
/// reading the bytes.
fn hash(hasher: &mut blake3::Hasher, bytes: &[u8]) {
    if bytes.len() >= 1 << 20 {
        hasher.update_rayon(bytes);
    } else {
        hasher.update(bytes);
    }
}

/// Where each section starts: the first after the table, each on a
/// multiple of [`SECTION_ALIGN`] bytes so a mapped section can be used in
/// place. The padding is zero, and checksummed like everything else.
pub fn section_offsets(sections: &[SectionInfo]) -> Option<(Vec<u64>, u64)> {
    let mut at = (HEADER_BYTES + sections.len() * TABLE_ROW_BYTES) as u64;
    let mut offsets = Vec::with_capacity(sections.len());
    for s in sections {
        at = at.checked_next_multiple_of(SECTION_ALIGN as u64)?;
        offsets.push(at);
        at = at.checked_add(s.length)?;
    }
    Some((offsets, at))
}

/// Reads and checks the header and table at the start of `file`.
pub fn read_header(file: &[u8]) -> Result<Header, Invalid> {
    let file_length = file.len() as u64;
    if file.len() < HEADER_BYTES {
        return Err(Invalid::Length(format!(
            "{file_length} bytes, shorter than the header"
        )));
    }
    let h = &file[..HEADER_BYTES];
    if h[0..8] != MAGIC {
        return Err(Invalid::Magic);
    }
    let u32_at = |i: usize| u32::from_le_bytes(h[i..i + 4].try_into().unwrap());
    if h[88..HEADER_BYTES].iter().any(|&b| b != 0) {
        return Err(Invalid::Malformed(
            "reserved header bytes are not zero".into(),
        ));
    }
    let version = u32_at(8);
    if version != FORMAT_VERSION {
        return Err(Invalid::Version(version));
    }
    let count = u32_at(12);
    if count > MAX_SECTIONS {
        return Err(Invalid::Malformed(format!("{count} sections")));
    }
    let table_end = HEADER_BYTES + count as usize * TABLE_ROW_BYTES;
    let table = file
        .get(HEADER_BYTES..table_end)
        .ok_or_else(|| Invalid::Length("the section table is cut short".into()))?;
    let sections: Vec<SectionInfo> = table
        .chunks_exact(TABLE_ROW_BYTES)
        .map(|row| SectionInfo {
            kind: u32::from_le_bytes(row[0..4].try_into().unwrap()),
            record_bytes: u32::from_le_bytes(row[4..8].try_into().unwrap()),
            length: u64::from_le_bytes(row[8..16].try_into().unwrap()),
        })
        .collect();
    let (offsets, end) = section_offsets(&sections)
        .ok_or_else(|| Invalid::Length("section lengths overflow".into()))?;
    let header = Header {
        key: h[16..48].try_into().unwrap(),
        payload_length: u64::from_le_bytes(h[48..56].try_into().unwrap()),
        checksum: h[56..88].try_into().unwrap(),
        sections,
        offsets,
    };
    if header.payload_length != end - table_end as u64 {
        return Err(Invalid::Length(
            "the section lengths do not add up to the payload".into(),
        ));
    }
    if end != file_length {
        return Err(Invalid::Length(format!(
            "{file_length} bytes, the header says {end}"
        )));
    }
    Ok(header)
}

/// Takes the sections of a mapped entry in order, checking each one's kind
/// and record size, and the checksum once all are taken.
pub struct SectionReader<'h> {
    map: &'h Arc<memmap2::Mmap>,
    header: &'h Header,
    next: usize,
    /// The end of the last section taken: hashing resumes there.
    at: usize,
    hasher: blake3::Hasher,
}

impl<'h> SectionReader<'h> {
    /// A reader over the sections of `header`, the checked header of `map`.
    pub fn new(map: &'h Arc<memmap2::Mmap>, header: &'h Header) -> Self {
        let mut hasher = blake3::Hasher::new();
        hasher.update(&Header::table_bytes(&header.sections));
        SectionReader {
            map,
            header,
            next: 0,
            at: HEADER_BYTES + header.sections.len() * TABLE_ROW_BYTES,
            hasher,
        }
    }

    /// The next section, which must be of `kind` with records of type `T`.
    pub fn take<T: Pod>(&mut self, kind: u32) -> Result<PodArray<T>, Invalid> {
        let index = self.next;
        let info = *self
            .header
            .sections
            .get(index)
            .ok_or_else(|| Invalid::Malformed(format!("section {kind} is missing")))?;
        self.next += 1;
        let size = std::mem::size_of::<T>();
        if info.kind != kind || info.record_bytes as usize != size {
            return Err(Invalid::Malformed(format!(
                "section {index} holds kind {} of {} bytes per record, expected kind {kind} of {size}",
                info.kind, info.record_bytes
            )));
        }
        if info.length % size as u64 != 0 {
            return Err(Invalid::Malformed(format!(
                "section {kind} is not a whole number of records"
            )));
        }
        let offset = self.header.offsets[index] as usize;
        let records = PodArray::from_map(self.map, offset, info.length as usize / size)
            .ok_or_else(|| Invalid::Malformed(format!("section {kind} is misaligned")))?;
        self.hasher.update(&self.map[self.at..offset]);
        hash(&mut self.hasher, bytemuck::cast_slice(&records));
        self.at = offset + info.length as usize;
        Ok(records)
    }

    /// Checks that every section was taken and the checksum matches.
    pub fn finish(self) -> Result<(), Invalid> {
        if self.next != self.header.sections.len() {
            return Err(Invalid::Malformed(format!(
                "{} sections, expected {}",
                self.header.sections.len(),
                self.next
            )));
        }
        if *self.hasher.finalize().as_bytes() != self.header.checksum {
            return Err(Invalid::Checksum);
        }
        Ok(())
    }
}
