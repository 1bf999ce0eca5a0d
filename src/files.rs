//! Reading files a user names, safely: only regular files, never more than a bound, and file
//! text escaped before it reaches a message. Every reader of input (meshes, stroke files,
//! stencils) goes through [`read_input`]; every message that quotes a file goes through
//! [`escape`].

use std::borrow::Cow;
use std::fs;
use std::io::{self, Read};
use std::path::Path;

/// The largest file slayer reads (4 GiB): far above any mesh it can sculpt in memory, low enough
/// that a mistaken path (a disk image, a link to `/dev/zero`) is refused before it is read.
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Reads the whole of `path` when it is a regular file of at most `limit` bytes. FIFOs,
/// devices, sockets and folders are refused before they are opened for reading (a FIFO would
/// block, a device never ends), and the size is checked before anything is read. The error
/// says what is wrong in words; the caller adds the path.
pub fn read_input(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    // Metadata follows links, so a link to a device is judged as the device.
    let before = fs::metadata(path)?;
    check_regular(&before)?;
    check_size(before.len(), limit)?;
    let file = open_without_blocking(path)?;
    // The path may have been swapped between the two looks: judge what was opened.
    let opened = file.metadata()?;
    check_regular(&opened)?;
    check_size(opened.len(), limit)?;
    let mut bytes = Vec::with_capacity(opened.len() as usize);
    // A file growing while it is read still stops one byte past the bound.
    file.take(limit + 1).read_to_end(&mut bytes)?;
    check_size(bytes.len() as u64, limit)?;
    Ok(bytes)
}

/// [`read_input`] as UTF-8 text.
pub fn read_input_text(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_input(path, limit)?).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "not a text file (invalid UTF-8 at byte {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

#[cfg(unix)]
fn open_without_blocking(path: &Path) -> io::Result<fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    // O_NONBLOCK: had a FIFO taken the file's place, opening it must not wait for a writer.
    fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
}

#[cfg(not(unix))]
fn open_without_blocking(path: &Path) -> io::Result<fs::File> {
    fs::File::open(path)
}

fn check_regular(metadata: &fs::Metadata) -> io::Result<()> {
    if metadata.is_file() {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "not a regular file ({}); slayer reads only regular files",
            kind_of(metadata)
        ),
    ))
}

fn check_size(size: u64, limit: u64) -> io::Result<()> {
    if size <= limit {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!(
            "{} is larger than {}, the most slayer reads for such a file",
            bytes_in_words(size),
            bytes_in_words(limit)
        ),
    ))
}

/// What kind of file `metadata` describes, in words.
fn kind_of(metadata: &fs::Metadata) -> &'static str {
    let kind = metadata.file_type();
    if kind.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_char_device() {
            return "a character device";
        }
        if kind.is_block_device() {
            return "a block device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    "not a plain file"
}

/// A byte count for messages: exact below 1 KiB, else in KiB, MiB or GiB with one decimal.
pub fn bytes_in_words(bytes: u64) -> String {
    const UNITS: [(&str, u64); 3] = [("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (unit, size) in UNITS {
        if bytes >= size {
            return format!("{:.1} {unit}", bytes as f64 / size as f64);
        }
    }
    format!("{bytes} bytes")
}

/// `text` with control characters escaped (`\u{1b}`, `\n`, …), so that bytes from a file can
/// never drive the terminal a message is printed on. Other characters pass unchanged.
pub fn escape(text: &str) -> Cow<'_, str> {
    if !text.chars().any(char::is_control) {
        return Cow::Borrowed(text);
    }
    let mut escaped = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() {
            escaped.extend(c.escape_default());
        } else {
            escaped.push(c);
        }
    }
    Cow::Owned(escaped)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_leaves_plain_text_and_defuses_control_characters() {
        assert_eq!(escape("layer 1 `é`"), "layer 1 `é`");
        let hostile = "a\u{1b}[31mred\u{7}\n";
        let escaped = escape(hostile);
        assert!(!escaped.chars().any(char::is_control), "{escaped}");
        assert_eq!(escaped, "a\\u{1b}[31mred\\u{7}\\n");
    }

    #[test]
    fn sizes_read_in_words() {
        assert_eq!(bytes_in_words(12), "12 bytes");
        assert_eq!(bytes_in_words(MAX_INPUT_BYTES), "4.0 GiB");
        assert_eq!(bytes_in_words(3 << 20), "3.0 MiB");
    }

    #[test]
    fn folders_and_oversized_files_are_refused_before_reading() {
        let dir = std::env::temp_dir().join(format!("slayer-files-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let error = read_input(&dir, MAX_INPUT_BYTES).unwrap_err();
        assert!(error.to_string().contains("a folder"), "{error}");
        let file = dir.join("ten.txt");
        fs::write(&file, b"0123456789").unwrap();
        assert_eq!(read_input(&file, 10).unwrap(), b"0123456789");
        let error = read_input(&file, 9).unwrap_err();
        assert!(error.to_string().contains("larger than"), "{error}");
        fs::remove_dir_all(dir).unwrap();
    }
}
