//! Reading a scene file from disk without hanging, without unbounded memory, and with errors
//! that say what the path is.
//!
//! Only regular files are read. The kind of the path is checked from its metadata before it is
//! opened, so a FIFO (which would block until a writer comes), a device (`/dev/zero` never
//! ends) or a folder is refused with its kind named, and never opened. The file is then opened
//! non-blocking and checked again, so a path swapped for a FIFO in between cannot block either.
//! Files over [`MAX_SCENE_BYTES`] are refused before they are read (a scene file is a few
//! kilobytes; the largest grid's pin list fits well under the cap), and the read itself stops
//! at the cap should the file grow meanwhile. Text must be UTF-8; a UTF-8 byte-order mark is
//! accepted, a UTF-16 one is named.

use std::fs::{File, Metadata, OpenOptions};
use std::io::Read;
use std::path::Path;

use crate::SceneError;

/// The largest scene file read, in bytes (64 MiB).
pub const MAX_SCENE_BYTES: u64 = 64 * 1024 * 1024;

/// What a path is, in words, when it is not a regular file; `None` for a regular file. Shared
/// with the other files clothsim reads (a state to carry on from), so they are refused alike.
pub fn special_kind(meta: &Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a folder");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// Checks that `path` is a regular file of at most [`MAX_SCENE_BYTES`], without opening it.
///
/// The UI's open dialog and the command line share this check, so neither can block on a FIFO
/// or read a device.
///
/// # Errors
/// [`SceneError::Io`] when the path cannot be looked at, [`SceneError::NotRegular`] naming
/// its kind, [`SceneError::TooLarge`] with the size and the cap.
pub fn check_scene_path(path: &Path) -> Result<Metadata, SceneError> {
    let meta = std::fs::metadata(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })?;
    check_metadata(path, meta)
}

fn check_metadata(path: &Path, meta: Metadata) -> Result<Metadata, SceneError> {
    if let Some(kind) = special_kind(&meta) {
        return Err(SceneError::NotRegular {
            path: path.to_owned(),
            kind,
        });
    }
    if meta.len() > MAX_SCENE_BYTES {
        return Err(SceneError::TooLarge {
            path: path.to_owned(),
            size: meta.len(),
            limit: MAX_SCENE_BYTES,
        });
    }
    Ok(meta)
}

/// Reads the scene file at `path` as text, with the checks in the module doc.
///
/// # Errors
/// As [`check_scene_path`], plus [`SceneError::Io`] for a failed read and
/// [`SceneError::NotText`] for text that is not UTF-8.
pub fn read_scene_file(path: &Path) -> Result<String, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_owned(),
        source,
    };
    check_scene_path(path)?;
    let mut options = OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // NOTE: should the path have become a FIFO since the check, opening it non-blocking
        // returns at once instead of waiting for a writer; the check below then refuses it.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file: File = options.open(path).map_err(io)?;
    let meta = check_metadata(path, file.metadata().map_err(io)?)?;
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(MAX_SCENE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(SceneError::TooLarge {
            path: path.to_owned(),
            size: bytes.len() as u64,
            limit: MAX_SCENE_BYTES,
        });
    }
    decode(path, bytes)
}

/// The UTF-8 text of `bytes`, without a byte-order mark.
fn decode(path: &Path, bytes: Vec<u8>) -> Result<String, SceneError> {
    utf8_text(bytes).map_err(|reason| SceneError::NotText {
        path: path.to_owned(),
        reason,
    })
}

/// The UTF-8 text of `bytes` without a UTF-8 byte-order mark, or what the bytes are instead
/// (UTF-16 text, or the first byte that is not UTF-8), in words. Shared with the other files
/// clothsim reads, so they get the same message.
///
/// # Errors
/// The reason the bytes are not UTF-8 text.
pub fn utf8_text(mut bytes: Vec<u8>) -> Result<String, String> {
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) {
        return Err(
            "it is UTF-16 text (it starts with a UTF-16 byte-order mark); save it as UTF-8"
                .to_owned(),
        );
    }
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        bytes.drain(..3);
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "it is not UTF-8 text (byte {} is not valid UTF-8)",
            e.utf8_error().valid_up_to() + 1
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_refused_with_its_kind_named() {
        let dir = std::env::temp_dir();
        let e = read_scene_file(&dir).unwrap_err();
        assert!(
            e.to_string().ends_with("is a folder, not a scene file"),
            "{e}"
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_device_is_refused_without_reading_it() {
        let e = read_scene_file(Path::new("/dev/zero")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/dev/zero is a character device, not a scene file"
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_at_once_instead_of_waiting_for_a_writer() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("scene.json");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(status.success());
        // Were the FIFO opened for reading, this would wait for a writer forever.
        let e = read_scene_file(&fifo).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("scene.json is a FIFO (named pipe), not a scene file"),
            "{e}"
        );
    }

    #[test]
    fn a_file_over_the_cap_is_refused_before_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.json");
        let f = File::create(&big).unwrap();
        // A sparse file: the size is what is checked, nothing is read.
        f.set_len(MAX_SCENE_BYTES + 1).unwrap();
        let e = read_scene_file(&big).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "big.json is 67108865 bytes; scene files are read up to 64 MiB (67108864 bytes)"
            ),
            "{e}"
        );
    }

    #[test]
    fn a_utf8_byte_order_mark_is_accepted_and_utf16_or_binary_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.json");
        std::fs::write(&p, b"\xEF\xBB\xBF{}").unwrap();
        assert_eq!(read_scene_file(&p).unwrap(), "{}");
        std::fs::write(&p, b"\xFF\xFE{\0}\0").unwrap();
        let e = read_scene_file(&p).unwrap_err().to_string();
        assert!(e.contains("UTF-16"), "{e}");
        std::fs::write(&p, b"{\"a\": \xC3}").unwrap();
        let e = read_scene_file(&p).unwrap_err().to_string();
        assert!(e.contains("byte 7 is not valid UTF-8"), "{e}");
    }
}
