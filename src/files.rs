//! Opening the files a scene names. Only regular files are read: a device
//! or a named pipe (`/dev/zero`, a FIFO) would be read forever or whole
//! into memory, so it is refused before a byte is read.

use std::fs::File;
use std::io;
use std::path::Path;

/// Opens `path` for reading if it is a regular file (after following
/// symbolic links); anything else is an `InvalidInput` error saying what
/// it is.
pub fn open_regular(path: &Path) -> io::Result<File> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        let what = if metadata.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device, pipe or socket)"
        };
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("is {what}"),
        ));
    }
    File::open(path)
}

/// Reads a whole regular file as text.
pub fn read_regular_to_string(path: &Path) -> io::Result<String> {
    use std::io::Read;
    let mut text = String::new();
    open_regular(path)?.read_to_string(&mut text)?;
    Ok(text)
}
