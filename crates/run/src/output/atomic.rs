//! Writing result files atomically, without changing what kind of file they are.
//!
//! The bytes go to a temporary file in the result's folder, which is flushed to disk and renamed
//! over the result ([`atomic_write_file`]), so a crash, a kill or a full disk never leaves a
//! half-written file where a good one was. On Linux the temporary file has no name until it is
//! complete (`O_TMPFILE`), so an interrupted write leaves nothing behind to clean up; elsewhere,
//! or on a file system without unnamed files, a kill mid-write can leave a `.NAME.XXXXXX` file
//! beside the result. Around that:
//!
//! - A symlink is followed and its target written (the link stays a link).
//! - An existing file keeps its permission bits and owner; a new file gets the mode a plain
//!   create gives (0666 less the umask).
//! - A file with several names (hard links) is replaced like any other: the name written gets
//!   the new contents and the other names keep the old ones, which [`Written::note`] says.
//!   Writing it in place instead would let a full disk or a kill destroy the contents every
//!   name shares.
//! - When the folder does not let us create the temporary file (a read-only folder holding a
//!   writable file) or the file's owner cannot be kept, the file is written in place, which is
//!   not atomic, and [`Written::note`] says so. The bytes past the old end are written first, so
//!   a full disk is found while the old contents are still whole.
//! - FIFOs, devices and sockets are refused before any work ([`check_target`]): a FIFO without
//!   a reader would block the write forever, and a result is a file.
//! - Before a run, [`check_target`] proves the write can happen: the name fits with the
//!   temporary file's suffix and the folder takes a new file (a probe is made and removed).

use std::fs::{self, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use atomic_write_file::AtomicWriteFile;

/// How many symlinks are followed before giving up (Linux's own limit).
const MAX_SYMLINKS: usize = 40;

/// How a file was written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Written {
    /// Atomically: a temporary file renamed over the result.
    Replaced,
    /// Atomically, over a file with other names (hard links), which keep the old contents; the
    /// text says so.
    Unlinked(String),
    /// In place, not atomically, for the reason given.
    InPlace(String),
}

impl Written {
    /// What a user should be told about the write, if anything.
    pub fn note(&self) -> Option<&str> {
        match self {
            Written::InPlace(why) | Written::Unlinked(why) => Some(why),
            Written::Replaced => None,
        }
    }

    /// [`Written::Replaced`], or [`Written::Unlinked`] when `existing` had other names.
    fn replaced(path: &Path, existing: Option<&fs::Metadata>) -> Self {
        match existing.map(link_count) {
            Some(n) if n > 1 => Written::Unlinked(format!(
                "{} had {n} names (hard links); it was replaced whole, so the other names still \
                 show the old contents",
                path.display()
            )),
            _ => Written::Replaced,
        }
    }
}

#[cfg(unix)]
fn link_count(m: &fs::Metadata) -> u64 {
    std::os::unix::fs::MetadataExt::nlink(m)
}

#[cfg(not(unix))]
fn link_count(_: &fs::Metadata) -> u64 {
    1
}

/// The file a write to `path` reaches: `path` with every symlink on it followed (a dangling
/// link gives the path it points to, which the write creates).
///
/// # Errors
/// A link that cannot be read, or more than [`MAX_SYMLINKS`] links in a chain.
fn resolve(path: &Path) -> anyhow::Result<PathBuf> {
    let mut p = path.to_owned();
    for _ in 0..MAX_SYMLINKS {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = fs::read_link(&p)
                    .with_context(|| format!("{}: cannot read the symlink", p.display()))?;
                p = match p.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            _ => return Ok(p),
        }
    }
    bail!(
        "{}: more than {MAX_SYMLINKS} symlinks in a chain (a loop?)",
        path.display()
    )
}

/// The longest file name the common file systems take, bytes.
const NAME_MAX: usize = 255;

/// Bytes the temporary file's name (`.NAME.XXXXXX`) adds to the result's name.
const TEMPORARY_EXTRA: usize = 8;

/// Checks, before any work is done, that `path` can be a result file, so a long run never ends
/// in a write that was bound to fail: not a folder, not a FIFO, device or socket (a FIFO
/// without a reader would block; results are files), in a folder that exists, with a name
/// short enough for the temporary file it is first written as, in a folder that takes a new
/// file of that name (a probe is created and removed). An existing regular file in a folder
/// that takes no new file passes when it can be opened for writing: it is then written in
/// place (see the module doc).
///
/// # Errors
/// Naming `path` and what is wrong, once.
pub fn check_target(path: &Path) -> anyhow::Result<()> {
    let target = resolve(path)?;
    let Some(name) = target.file_name() else {
        bail!("{}: give a file name, such as state.json", path.display());
    };
    let bytes = name.as_encoded_bytes().len();
    if bytes + TEMPORARY_EXTRA > NAME_MAX {
        bail!(
            "{}: the file name is {bytes} bytes, too long: it is first written under a temporary \
             name {TEMPORARY_EXTRA} bytes longer, and file names are limited to {NAME_MAX} bytes, \
             so at most {} bytes are allowed",
            path.display(),
            NAME_MAX - TEMPORARY_EXTRA
        );
    }
    // A path that cannot be looked at (a missing folder, a file used as a folder) is told by
    // the folder's check below, or by the probe.
    let existing = fs::metadata(&target).ok();
    if existing.as_ref().is_some_and(fs::Metadata::is_dir) {
        bail!(
            "{} is a folder; give a file name, such as {}",
            path.display(),
            path.join("state.json").display()
        );
    }
    // A folder was refused above; the scene crate's words name every other kind alike.
    if let Some(kind) = existing.as_ref().and_then(cloth_scene::special_kind) {
        bail!(
            "{} is {kind}; results are written to regular files (without --out a state goes to \
             standard output, which can be piped)",
            path.display()
        );
    }
    let dir = parent_of(&target);
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => bail!("{}: {} is not a folder", path.display(), dir.display()),
        Err(e) => bail!(
            "{}: the folder {} cannot be used: {e}",
            path.display(),
            dir.display()
        ),
    }
    probe(path, dir, name, existing.is_some())
}

/// Creates and removes a file in `dir` named like the temporary file of a result called
/// `name` (`.NAME.XXXXXX`), proving the folder takes it. When it does not and the result
/// exists, the result must open for writing (it will be written in place).
fn probe(path: &Path, dir: &Path, name: &std::ffi::OsStr, exists: bool) -> anyhow::Result<()> {
    use std::sync::atomic::{AtomicU32, Ordering};
    static COUNT: AtomicU32 = AtomicU32::new(0);
    let mut last = None;
    for _ in 0..16 {
        // Six characters, as the temporary file's suffix has: unique within this process by
        // the counter, between processes by the process id.
        let n =
            u64::from(std::process::id()) * 4096 + u64::from(COUNT.fetch_add(1, Ordering::Relaxed));
        let mut probe_name = std::ffi::OsString::from(".");
        probe_name.push(name);
        probe_name.push(format!(".{:06}", n % 1_000_000));
        let probe_path = dir.join(&probe_name);
        match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&probe_path)
        {
            Ok(f) => {
                drop(f);
                fs::remove_file(&probe_path).with_context(|| {
                    format!("{}: cannot remove the probe file", probe_path.display())
                })?;
                return Ok(());
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => {
                use std::io::ErrorKind::{PermissionDenied, ReadOnlyFilesystem};
                if exists && matches!(e.kind(), PermissionDenied | ReadOnlyFilesystem) {
                    // Written in place: the file itself must take the bytes.
                    return OpenOptions::new()
                        .write(true)
                        .open(path)
                        .map(drop)
                        .with_context(|| {
                            format!(
                                "{}: the folder {} does not take new files ({e}) and the file \
                                 cannot be written either",
                                path.display(),
                                dir.display()
                            )
                        });
                }
                return Err(anyhow::Error::new(e).context(format!(
                    "{}: cannot create a file in the folder {}; choose a folder you can write to",
                    path.display(),
                    dir.display()
                )));
            }
        }
    }
    bail!(
        "{}: cannot create a probe file in {}: every name tried is taken ({})",
        path.display(),
        dir.display(),
        last.map_or_else(String::new, |e| e.to_string())
    )
}

fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// The resolved target of a write to `path` and its metadata, `None` for a new file.
fn target_of(path: &Path) -> anyhow::Result<(PathBuf, Option<fs::Metadata>)> {
    check_target(path)?;
    let target = resolve(path)?;
    match fs::metadata(&target) {
        Ok(m) => Ok((target, Some(m))),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok((target, None)),
        Err(e) => Err(anyhow::Error::new(e).context(format!("{}: cannot write", path.display()))),
    }
}

/// A temporary file that becomes `target` on commit, keeping an existing file's mode and
/// owner: an error when the owner cannot be kept (only the superuser may give a file away).
fn open_temporary(target: &Path, keep_owner: bool) -> std::io::Result<AtomicWriteFile> {
    let mut options = AtomicWriteFile::options();
    // Read back when the bytes must go in place after all (see `StreamFile::finish`).
    options.read(true);
    #[cfg(unix)]
    {
        use atomic_write_file::unix::OpenOptionsExt;
        options.preserve_mode(true).preserve_owner(keep_owner);
    }
    #[cfg(not(unix))]
    let _ = keep_owner;
    options.open(target)
}

/// What to do instead when no temporary file that keeps the owner can be made for an existing
/// file: the note for a write in place, or `None` when the cause is not one a write in place
/// gets around.
fn in_place_instead(path: &Path, target: &Path, e: &std::io::Error) -> Option<String> {
    use std::io::ErrorKind::{PermissionDenied, ReadOnlyFilesystem};
    if !matches!(e.kind(), PermissionDenied | ReadOnlyFilesystem) {
        return None;
    }
    // Without the owner, a temporary file can be made: the owner was the obstacle.
    Some(if open_temporary(target, false).is_ok() {
        format!(
            "{} belongs to another user or group that a new file cannot be given, so it was \
             written in place, not atomically, to keep its owner",
            path.display()
        )
    } else {
        format!(
            "{} does not allow new files ({e}), so {} was written in place, not atomically",
            parent_of(target).display(),
            path.display()
        )
    })
}

/// Writes `bytes` to `path` atomically where it can, keeping what kind of file `path` is (see
/// the module doc); [`Written`] says how it went.
///
/// # Errors
/// Naming `path` and the cause, once: a folder given as the file, a missing folder, no
/// permission, a full disk.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<Written> {
    let (target, existing) = target_of(path)?;
    let mut file = match open_temporary(&target, true) {
        Ok(f) => f,
        Err(e) => {
            let dir = parent_of(&target);
            let why = existing
                .is_some()
                .then(|| in_place_instead(path, &target, &e))
                .flatten();
            let Some(why) = why else {
                return Err(anyhow::Error::new(e).context(format!(
                    "{}: cannot create a file in {}",
                    path.display(),
                    dir.display()
                )));
            };
            write_in_place(path, &target, bytes).with_context(|| {
                format!(
                    "{}: cannot create a temporary file in {} ({e}) and cannot write the file \
                     in place either",
                    path.display(),
                    dir.display()
                )
            })?;
            return Ok(Written::InPlace(why));
        }
    };
    file.write_all(bytes)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    file.commit().with_context(|| {
        format!(
            "{}: cannot move the new contents into place",
            path.display()
        )
    })?;
    Ok(Written::replaced(path, existing.as_ref()))
}

/// A result file written piece by piece (a frame at a time), then put in place whole.
///
/// The same temporary file as [`write_atomic`]'s receives the bytes; [`StreamFile::finish`]
/// syncs it and renames it over the result, keeping the old file's mode and owner. Dropped
/// unfinished (an error, a panic) it is removed, and the old file stays as it was; ended by a
/// signal or a kill, it leaves nothing on Linux (see the module doc). When the result's owner
/// cannot be kept, the finished bytes are copied in place instead. It can seek, so a header can
/// be completed at the end.
pub struct StreamFile {
    path: PathBuf,
    target: PathBuf,
    existing: Option<fs::Metadata>,
    /// Why the finished bytes must be copied in place, when they must.
    in_place: Option<String>,
    out: std::io::BufWriter<AtomicWriteFile>,
}

impl std::fmt::Debug for StreamFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamFile")
            .field("path", &self.path)
            .field("target", &self.target)
            .finish_non_exhaustive()
    }
}

impl StreamFile {
    /// Starts writing `path` (see the type's doc).
    ///
    /// # Errors
    /// Naming `path` and the cause, once: a folder given as the file, a missing or
    /// read-only folder, a FIFO or device (a stream that is put in place at the end must be a
    /// regular file).
    pub fn create(path: &Path) -> anyhow::Result<Self> {
        let (target, existing) = target_of(path)?;
        let cannot_create = |e: std::io::Error| {
            anyhow::Error::new(e).context(format!(
                "{}: cannot create a file in {}",
                path.display(),
                parent_of(&target).display()
            ))
        };
        let (file, in_place) = match open_temporary(&target, true) {
            Ok(f) => (f, None),
            // Only an owner that cannot be kept is got around: a folder that does not allow
            // new files cannot hold the stream's bytes either.
            Err(e) if existing.is_some() && e.kind() == std::io::ErrorKind::PermissionDenied => {
                let f = open_temporary(&target, false).map_err(cannot_create)?;
                let why = in_place_instead(path, &target, &e);
                (f, why)
            }
            Err(e) => return Err(cannot_create(e)),
        };
        Ok(Self {
            path: path.to_owned(),
            target,
            existing,
            in_place,
            out: std::io::BufWriter::with_capacity(256 * 1024, file),
        })
    }

    /// The result's path, as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Puts the written bytes in place as the result (see the type's doc).
    ///
    /// # Errors
    /// Naming the result and the cause: a full disk, a rename refused.
    pub fn finish(self) -> anyhow::Result<Written> {
        let Self {
            path,
            target,
            existing,
            in_place,
            out,
        } = self;
        let mut file = out
            .into_inner()
            .map_err(|e| anyhow::Error::new(e.into_error()))
            .with_context(|| format!("{}: cannot write", path.display()))?;
        if let Some(why) = in_place {
            let mut bytes = Vec::new();
            file.seek(SeekFrom::Start(0))
                .and_then(|_| file.read_to_end(&mut bytes))
                .with_context(|| format!("{}: cannot read back", path.display()))?;
            drop(file);
            write_in_place(&path, &target, &bytes)?;
            return Ok(Written::InPlace(why));
        }
        file.commit().with_context(|| {
            format!(
                "{}: cannot move the new contents into place",
                path.display()
            )
        })?;
        Ok(Written::replaced(&path, existing.as_ref()))
    }
}

impl Write for StreamFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out.write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.out.write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

impl Seek for StreamFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.out.seek(pos)
    }
}

/// Overwrites `target` (the resolved `path`) in place.
///
/// A regular file gets the bytes past its old end first: a full disk shows there, and the file
/// is cut back to its old length, whole. The rest overwrites blocks the file already has, which
/// needs no new space on a file system that writes in place (not on a copy-on-write one).
fn write_in_place(path: &Path, target: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let cannot = || format!("{}: cannot write", path.display());
    let mut options = OpenOptions::new();
    options.write(true).create(true).truncate(false);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // NOTE: should the path have become a FIFO since it was checked, a non-blocking open
        // fails at once instead of waiting for a reader; a regular file ignores the flag.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let mut f = options
        .open(target)
        .with_context(|| format!("{}: cannot open for writing", path.display()))?;
    let old = match f.metadata() {
        Ok(m) if m.is_file() => m.len(),
        _ => bail!(
            "{}: not a regular file; results are written to files",
            path.display()
        ),
    };
    let keep = usize::try_from(old).map_or(bytes.len(), |old| old.min(bytes.len()));
    let (head, tail) = bytes.split_at(keep);
    if !tail.is_empty() {
        let grown = f
            .seek(SeekFrom::Start(old))
            .and_then(|_| f.write_all(tail))
            .and_then(|()| f.sync_data());
        if let Err(e) = grown {
            // Back to the old contents, whole.
            let _ = f.set_len(old).and_then(|()| f.sync_all());
            return Err(anyhow::Error::new(e).context(cannot()));
        }
    }
    f.seek(SeekFrom::Start(0))
        .and_then(|_| f.write_all(head))
        .and_then(|()| f.set_len(bytes.len() as u64))
        .and_then(|()| f.sync_all())
        .with_context(cannot)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_written_file_holds_the_bytes_and_replaces_the_old_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.json");
        assert_eq!(write_atomic(&path, b"old").unwrap(), Written::Replaced);
        assert_eq!(write_atomic(&path, b"new").unwrap(), Written::Replaced);
        assert_eq!(fs::read(&path).unwrap(), b"new");
        // Nothing else is left in the folder: the temporary file became the result.
        assert_eq!(names(dir.path()), ["out.json"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_new_file_has_the_mode_of_a_plain_create() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let (ours, plain) = (dir.path().join("ours"), dir.path().join("plain"));
        write_atomic(&ours, b"x").unwrap();
        fs::write(&plain, b"x").unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o7777;
        assert_eq!(mode(&ours), mode(&plain));
    }

    #[cfg(unix)]
    #[test]
    fn an_existing_file_keeps_its_mode_private_or_executable() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        for mode in [0o600, 0o755, 0o640] {
            let path = dir.path().join(format!("f{mode:o}"));
            fs::write(&path, b"old").unwrap();
            fs::set_permissions(&path, fs::Permissions::from_mode(mode)).unwrap();
            write_atomic(&path, b"new").unwrap();
            let got = fs::metadata(&path).unwrap().permissions().mode() & 0o7777;
            assert_eq!(got, mode, "{mode:o}");
            assert_eq!(fs::read(&path).unwrap(), b"new");
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_stays_a_link_and_its_target_gets_the_contents() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.json");
        let link = dir.path().join("link.json");
        fs::write(&real, b"old").unwrap();
        std::os::unix::fs::symlink("real.json", &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(
            fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(fs::read(&real).unwrap(), b"new");
        // A dangling link creates its target.
        let dangling = dir.path().join("dangling.json");
        std::os::unix::fs::symlink("made.json", &dangling).unwrap();
        write_atomic(&dangling, b"made").unwrap();
        assert_eq!(fs::read(dir.path().join("made.json")).unwrap(), b"made");
        // A loop is an error, not a hang.
        let a = dir.path().join("a.json");
        std::os::unix::fs::symlink("b.json", &a).unwrap();
        std::os::unix::fs::symlink("a.json", dir.path().join("b.json")).unwrap();
        let e = write_atomic(&a, b"x").unwrap_err().to_string();
        assert!(e.contains("symlinks in a chain"), "{e}");
    }

    #[cfg(unix)]
    #[test]
    fn a_hard_linked_file_is_replaced_whole_and_the_note_says_the_other_names_keep_the_old() {
        let dir = tempfile::tempdir().unwrap();
        let one = dir.path().join("one.json");
        let two = dir.path().join("two.json");
        fs::write(&one, b"old").unwrap();
        fs::hard_link(&one, &two).unwrap();
        let w = write_atomic(&one, b"new contents").unwrap();
        let note = w.note().unwrap();
        assert!(note.contains("had 2 names (hard links)"), "{w:?}");
        assert!(
            note.contains("other names still show the old contents"),
            "{w:?}"
        );
        assert_eq!(fs::read(&one).unwrap(), b"new contents");
        assert_eq!(fs::read(&two).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["one.json", "two.json"]);
    }

    #[test]
    fn a_write_in_place_that_grows_the_file_keeps_short_and_long_contents_right() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f");
        fs::write(&path, b"0123456789").unwrap();
        write_in_place(&path, &path, b"abc").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"abc");
        write_in_place(&path, &path, b"a longer text").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"a longer text");
        write_in_place(&path, &path, b"").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"");
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_device_or_a_fifo_is_refused_before_anything_is_written_or_waited_for() {
        let e = format!("{:#}", check_target(Path::new("/dev/full")).unwrap_err());
        assert!(e.contains("/dev/full is a character device"), "{e}");
        let e = format!(
            "{:#}",
            write_atomic(Path::new("/dev/null"), b"x").unwrap_err()
        );
        assert!(e.contains("/dev/null is a character device"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("out.json");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        // Opened for writing without a reader, a FIFO would block forever.
        let e = format!("{:#}", write_atomic(&fifo, b"x").unwrap_err());
        assert!(e.contains("out.json is a FIFO (named pipe)"), "{e}");
        let e = format!("{:#}", StreamFile::create(&fifo).unwrap_err());
        assert!(e.contains("is a FIFO"), "{e}");
    }

    #[test]
    fn a_name_that_leaves_no_room_for_the_temporary_suffix_is_refused_before_the_run() {
        let dir = tempfile::tempdir().unwrap();
        // 247 bytes and the temporary's 8 make 255, the limit: written whole.
        let fits = dir.path().join(format!("{}.json", "a".repeat(242)));
        check_target(&fits).unwrap();
        assert_eq!(write_atomic(&fits, b"x").unwrap(), Written::Replaced);
        assert_eq!(fs::read(&fits).unwrap(), b"x");
        // One byte more cannot be written atomically on a file system with 255-byte names:
        // said before the run, not after it.
        let long = dir.path().join(format!("{}.json", "a".repeat(243)));
        let e = format!("{:#}", check_target(&long).unwrap_err());
        assert!(
            e.contains("the file name is 248 bytes, too long") && e.contains("at most 247 bytes"),
            "{e}"
        );
        // Multi-byte characters count as their bytes: 124 two-byte letters are 248 bytes.
        let accented = dir.path().join("\u{e9}".repeat(124));
        let e = format!("{:#}", check_target(&accented).unwrap_err());
        assert!(e.contains("248 bytes"), "{e}");
        // The probe leaves nothing behind.
        assert_eq!(
            names(dir.path()),
            [fits.file_name().unwrap().to_str().unwrap()]
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_writable_file_in_a_read_only_folder_is_written_in_place_and_says_so() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("ro");
        fs::create_dir(&sub).unwrap();
        let path = sub.join("state.json");
        fs::write(&path, b"old").unwrap();
        fs::set_permissions(&sub, fs::Permissions::from_mode(0o555)).unwrap();
        // The superuser may create files in a read-only folder: then the write is atomic.
        let can_create = fs::File::create(sub.join("probe")).is_ok();
        let w = write_atomic(&path, b"new");
        fs::set_permissions(&sub, fs::Permissions::from_mode(0o755)).unwrap();
        let w = w.unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        if can_create {
            assert_eq!(w, Written::Replaced);
        } else {
            assert!(w.note().unwrap().contains("written in place"), "{w:?}");
        }
    }

    #[test]
    fn a_folder_is_refused_once_with_a_file_name_suggested() {
        let dir = tempfile::tempdir().unwrap();
        let e = format!("{:#}", write_atomic(dir.path(), b"x").unwrap_err());
        assert!(e.contains("is a folder; give a file name"), "{e}");
        assert!(!e.contains("os error"), "said once, in words: {e}");
        let e = format!(
            "{:#}",
            check_target(&dir.path().join("no/such/state.json")).unwrap_err()
        );
        assert!(e.contains("cannot be used"), "{e}");
    }

    #[test]
    fn a_streamed_file_appears_whole_on_finish_and_not_at_all_when_dropped() {
        use std::io::{Seek, SeekFrom};
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("anim.pc2");
        fs::write(&path, b"old").unwrap();
        let mut s = StreamFile::create(&path).unwrap();
        s.write_all(b"0000 body").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"old", "untouched while writing");
        s.seek(SeekFrom::Start(0)).unwrap();
        s.write_all(b"head").unwrap();
        assert_eq!(s.finish().unwrap(), Written::Replaced);
        assert_eq!(fs::read(&path).unwrap(), b"head body");
        assert_eq!(names(dir.path()), ["anim.pc2"]);

        let mut s = StreamFile::create(&path).unwrap();
        s.write_all(b"partial").unwrap();
        drop(s);
        assert_eq!(fs::read(&path).unwrap(), b"head body");
        assert_eq!(
            names(dir.path()),
            ["anim.pc2"],
            "the temporary file is gone"
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_streamed_file_keeps_the_mode_of_the_file_it_replaces() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("stats.csv");
        fs::write(&path, b"old").unwrap();
        fs::set_permissions(&path, fs::Permissions::from_mode(0o640)).unwrap();
        let mut s = StreamFile::create(&path).unwrap();
        s.write_all(b"new").unwrap();
        s.finish().unwrap();
        let got = fs::metadata(&path).unwrap().permissions().mode() & 0o7777;
        assert_eq!(got, 0o640);
    }
}
