//! Writing result files atomically, without changing what kind of file they are.
//!
//! The bytes go to a temporary file next to the result, `.NAME.clothsim-tmp.PID`, which is
//! flushed to disk and renamed over the result, so a crash, a kill or a full disk never leaves a
//! half-written file where a good one was. Around that:
//!
//! - A symlink is followed and its target written (the link stays a link).
//! - An existing file keeps its permission bits and, where the system allows it, its owner and
//!   group; a new file gets the mode a plain create gives (0666 less the umask).
//! - A file with several names (hard links) is written in place, so every name sees the new
//!   contents; replacing it would split the names apart, leaving the others on the old state.
//! - When the folder does not let us create the temporary file (a read-only folder holding a
//!   writable file) or the file's owner cannot be kept, the file is written in place.
//! - Writing in place is not atomic, so [`Written::note`] says when it happened.
//! - A temporary file is removed when SIGINT, SIGTERM or SIGHUP arrives mid-write (once
//!   [`cleanup_on_signals`] was called), and one left by a process that died otherwise (SIGKILL,
//!   a power cut) is removed by the next write into the same folder.
//! - FIFOs and devices are opened and written as they are.

use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, bail};

/// The middle of every temporary file's name, so a leftover is recognisable.
const TMP_MARK: &str = ".clothsim-tmp.";

/// How many symlinks are followed before giving up (Linux's own limit).
const MAX_SYMLINKS: usize = 40;

/// Temporary files being written, removed by the signal thread if a signal ends the process.
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// How a file was written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Written {
    /// Atomically: a temporary file renamed over the result.
    Replaced,
    /// In place, not atomically, for the reason given.
    InPlace(String),
    /// A FIFO or a device, opened and written as it is.
    Special,
}

impl Written {
    /// What a user should be told about the write, if anything.
    pub fn note(&self) -> Option<&str> {
        match self {
            Written::InPlace(why) => Some(why),
            Written::Replaced | Written::Special => None,
        }
    }
}

/// Removes temporary files when SIGINT, SIGTERM or SIGHUP ends the process mid-write.
///
/// For the headless commands, whose only response to these signals is to end: a thread waits
/// for them, removes every temporary file in flight, then ends the process as the signal's
/// default action would (the exit status still tells the shell which signal it was). The UI has
/// its own signal handling and its saves finish before it acts on a signal, so it does not call
/// this.
///
/// # Errors
/// When the signal handlers cannot be installed.
pub fn cleanup_on_signals() -> anyhow::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    let mut result = Ok(());
    INSTALLED.call_once(|| {
        let mut signals = match signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
            Ok(s) => s,
            Err(e) => {
                result = Err(anyhow::Error::new(e).context("cannot install signal handlers"));
                return;
            }
        };
        std::thread::spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let paths = IN_FLIGHT
                    .lock()
                    .map_or_else(|poisoned| poisoned.into_inner().clone(), |p| p.clone());
                for p in paths {
                    let _ = fs::remove_file(p);
                }
                let _ = signal_hook::low_level::emulate_default_handler(signal);
                // Only reached for a signal whose default is to carry on (none of ours).
                std::process::exit(128 + signal);
            }
        });
    });
    result
}

/// A temporary file registered for removal; removed on drop unless it was renamed.
struct TempFile {
    path: PathBuf,
    file: Option<File>,
    renamed: bool,
}

impl TempFile {
    /// Creates `.NAME.clothsim-tmp.PID` next to `target`, owner-only (`mode` 0600) or with the
    /// mode a new file gets (`0666` less the umask).
    fn create(dir: &Path, name: &str, mode: u32) -> std::io::Result<Self> {
        let pid = std::process::id();
        let mut attempt = 0u32;
        loop {
            let file_name = if attempt == 0 {
                format!(".{name}{TMP_MARK}{pid}")
            } else {
                // Another write of the same file by this process is in flight.
                format!(".{name}{TMP_MARK}{pid}.{attempt}")
            };
            let path = dir.join(file_name);
            register(&path);
            let mut options = OpenOptions::new();
            options.write(true).create_new(true);
            #[cfg(unix)]
            {
                use std::os::unix::fs::OpenOptionsExt;
                options.mode(mode);
            }
            #[cfg(not(unix))]
            let _ = mode;
            match options.open(&path) {
                Ok(file) => {
                    return Ok(Self {
                        path,
                        file: Some(file),
                        renamed: false,
                    });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempt < 100 => {
                    unregister(&path);
                    attempt += 1;
                }
                Err(e) => {
                    unregister(&path);
                    return Err(e);
                }
            }
        }
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        drop(self.file.take());
        if !self.renamed {
            let _ = fs::remove_file(&self.path);
        }
        unregister(&self.path);
    }
}

fn register(path: &Path) {
    if let Ok(mut v) = IN_FLIGHT.lock() {
        v.push(path.to_owned());
    }
}

fn unregister(path: &Path) {
    if let Ok(mut v) = IN_FLIGHT.lock() {
        v.retain(|p| p != path);
    }
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

/// Checks, before any work is done, that `path` can be a result file: not a folder, in a
/// folder that exists.
///
/// # Errors
/// Naming `path` and what is wrong, once.
pub fn check_target(path: &Path) -> anyhow::Result<()> {
    let target = resolve(path)?;
    if target.is_dir() {
        bail!(
            "{} is a folder; give a file name, such as {}",
            path.display(),
            path.join("state.json").display()
        );
    }
    let dir = parent_of(&target);
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => bail!("{}: {} is not a folder", path.display(), dir.display()),
        Err(e) => bail!(
            "{}: the folder {} cannot be used: {e}",
            path.display(),
            dir.display()
        ),
    }
}

fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Writes `bytes` to `path` atomically where it can, keeping what kind of file `path` is (see
/// the module doc); [`Written`] says how it went.
///
/// # Errors
/// Naming `path` and the cause, once: a folder given as the file, a missing folder, no
/// permission, a full disk.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<Written> {
    let target = resolve(path)?;
    let existing = match fs::metadata(&target) {
        Ok(m) => Some(m),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => {
            return Err(anyhow::Error::new(e).context(format!("{}: cannot write", path.display())));
        }
    };
    if let Some(m) = &existing {
        if m.is_dir() {
            check_target(path)?;
        }
        if !m.is_file() {
            write_in_place(path, &target, bytes)?;
            return Ok(Written::Special);
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            if m.nlink() > 1 {
                write_in_place(path, &target, bytes)?;
                return Ok(Written::InPlace(format!(
                    "{} has {} names (hard links), so it was written in place, not atomically, \
                     for every name to show the new contents",
                    path.display(),
                    m.nlink()
                )));
            }
        }
    }
    let dir = parent_of(&target);
    let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        bail!("{}: not a file name", path.display());
    };
    remove_leftovers(dir);
    // An existing file's contents may be private: the temporary file is owner-only until it
    // gets the old file's mode. A new file gets the mode a plain create gives.
    let mode = if existing.is_some() { 0o600 } else { 0o666 };
    let mut tmp = match TempFile::create(dir, &name, mode) {
        Ok(t) => t,
        Err(e)
            if existing.is_some()
                && matches!(
                    e.kind(),
                    std::io::ErrorKind::PermissionDenied | std::io::ErrorKind::ReadOnlyFilesystem
                ) =>
        {
            write_in_place(path, &target, bytes).with_context(|| {
                format!(
                    "{}: cannot create a temporary file in {} ({e}) and cannot write the file \
                     in place either",
                    path.display(),
                    dir.display()
                )
            })?;
            return Ok(Written::InPlace(format!(
                "{} does not allow new files ({e}), so {} was written in place, not atomically",
                dir.display(),
                path.display()
            )));
        }
        Err(e) => {
            return Err(anyhow::Error::new(e).context(format!(
                "{}: cannot create a file in {}",
                path.display(),
                dir.display()
            )));
        }
    };
    let Some(file) = tmp.file.as_mut() else {
        bail!("{}: the temporary file is gone", path.display());
    };
    if let Some(old) = &existing
        && !keep_owner(file, old)
    {
        drop(tmp);
        write_in_place(path, &target, bytes)?;
        return Ok(Written::InPlace(format!(
            "{} belongs to another user or group that a new file cannot be given, so it was \
             written in place, not atomically, to keep its owner",
            path.display()
        )));
    }
    let written = file
        .write_all(bytes)
        .and_then(|()| match &existing {
            Some(old) => file.set_permissions(old.permissions()),
            None => Ok(()),
        })
        .and_then(|()| file.sync_all());
    if let Err(e) = written {
        return Err(anyhow::Error::new(e).context(format!("{}: cannot write", path.display())));
    }
    drop(tmp.file.take());
    fs::rename(&tmp.path, &target).with_context(|| {
        format!(
            "{}: cannot move the new contents into place",
            path.display()
        )
    })?;
    tmp.renamed = true;
    // The rename is only durable once the folder's entry is on disk; where a folder cannot be
    // synced the file itself still is.
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(Written::Replaced)
}

/// A result file written piece by piece (a frame at a time), then put in place whole.
///
/// The same temporary file as [`write_atomic`]'s, `.NAME.clothsim-tmp.PID` next to the
/// result, receives the bytes; [`StreamFile::finish`] gives it the old file's mode and owner,
/// syncs it and renames it over the result. Dropped unfinished (an error, a panic) or ended by
/// a signal (once [`cleanup_on_signals`] was called), it is removed and the old file stays as
/// it was. A result with several names (hard links) gets the finished bytes copied in place,
/// so every name sees them. It can seek, so a header can be completed at the end.
pub struct StreamFile {
    path: PathBuf,
    target: PathBuf,
    existing: Option<fs::Metadata>,
    tmp: TempFile,
    out: std::io::BufWriter<File>,
}

impl std::fmt::Debug for StreamFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamFile")
            .field("path", &self.path)
            .field("tmp", &self.tmp.path)
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
        check_target(path)?;
        let target = resolve(path)?;
        let existing = match fs::metadata(&target) {
            Ok(m) => Some(m),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => {
                return Err(
                    anyhow::Error::new(e).context(format!("{}: cannot write", path.display()))
                );
            }
        };
        if existing.as_ref().is_some_and(|m| !m.is_file()) {
            bail!(
                "{}: not a regular file; this output is written to a file, then put in place",
                path.display()
            );
        }
        let dir = parent_of(&target);
        let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
            bail!("{}: not a file name", path.display());
        };
        remove_leftovers(dir);
        let mode = if existing.is_some() { 0o600 } else { 0o666 };
        let mut tmp = TempFile::create(dir, &name, mode).map_err(|e| {
            anyhow::Error::new(e).context(format!(
                "{}: cannot create a file in {}",
                path.display(),
                dir.display()
            ))
        })?;
        let Some(file) = tmp.file.take() else {
            bail!("{}: the temporary file is gone", path.display());
        };
        Ok(Self {
            path: path.to_owned(),
            target,
            existing,
            tmp,
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
            mut tmp,
            out,
        } = self;
        let file = out
            .into_inner()
            .map_err(|e| anyhow::Error::new(e.into_error()))
            .with_context(|| format!("{}: cannot write", path.display()))?;
        #[cfg(unix)]
        if let Some(old) = &existing {
            use std::os::unix::fs::MetadataExt;
            if old.nlink() > 1 || !keep_owner(&file, old) {
                drop(file);
                let bytes = fs::read(&tmp.path)
                    .with_context(|| format!("{}: cannot read back", path.display()))?;
                drop(tmp);
                write_in_place(&path, &target, &bytes)?;
                return Ok(Written::InPlace(format!(
                    "{} has other names (hard links) or an owner a new file cannot be given, so \
                     it was written in place, not atomically",
                    path.display()
                )));
            }
        }
        let synced = match &existing {
            Some(old) => file.set_permissions(old.permissions()),
            None => Ok(()),
        }
        .and_then(|()| file.sync_all());
        if let Err(e) = synced {
            return Err(anyhow::Error::new(e).context(format!("{}: cannot write", path.display())));
        }
        drop(file);
        fs::rename(&tmp.path, &target).with_context(|| {
            format!(
                "{}: cannot move the new contents into place",
                path.display()
            )
        })?;
        tmp.renamed = true;
        if let Ok(d) = File::open(parent_of(&target)) {
            let _ = d.sync_all();
        }
        Ok(Written::Replaced)
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

impl std::io::Seek for StreamFile {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.out.seek(pos)
    }
}

/// Gives the temporary file the old file's owner and group when they differ from ours; false
/// when the system does not allow it (only the superuser may give a file away).
#[cfg(unix)]
fn keep_owner(file: &File, old: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    let Ok(new) = file.metadata() else {
        return false;
    };
    if new.uid() == old.uid() && new.gid() == old.gid() {
        return true;
    }
    let uid = (new.uid() != old.uid()).then_some(old.uid());
    std::os::unix::fs::fchown(file, uid, Some(old.gid())).is_ok()
}

#[cfg(not(unix))]
fn keep_owner(_: &File, _: &fs::Metadata) -> bool {
    true
}

/// Overwrites `target` (the resolved `path`) in place.
fn write_in_place(path: &Path, target: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let mut f = OpenOptions::new()
        .write(true)
        .truncate(true)
        .create(true)
        .open(target)
        .with_context(|| format!("{}: cannot open for writing", path.display()))?;
    f.write_all(bytes)
        .and_then(|()| f.flush())
        .with_context(|| format!("{}: cannot write", path.display()))?;
    // A FIFO or a terminal cannot be synced; a regular file must be.
    if f.metadata().is_ok_and(|m| m.is_file()) {
        f.sync_all()
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}

/// Removes temporary files in `dir` left by clothsim processes that no longer run.
fn remove_leftovers(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let me = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = leftover_pid(&name.to_string_lossy()) else {
            continue;
        };
        if pid != me && !process_runs(pid) && entry.file_type().is_ok_and(|t| t.is_file()) {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// The process id in a temporary file's name (`.NAME.clothsim-tmp.PID` or `...PID.N`).
fn leftover_pid(name: &str) -> Option<u32> {
    if !name.starts_with('.') {
        return None;
    }
    let (_, tail) = name.rsplit_once(TMP_MARK)?;
    let digits = tail.split('.').next()?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// Whether a process with this id exists (one of another user counts).
#[cfg(unix)]
fn process_runs(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: signal 0 only asks whether the process exists and may be signalled; nothing is
    // sent and no memory is touched.
    #[allow(unsafe_code)]
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn process_runs(_: u32) -> bool {
    true
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
    fn a_hard_linked_file_is_written_in_place_so_every_name_sees_it_and_says_so() {
        let dir = tempfile::tempdir().unwrap();
        let one = dir.path().join("one.json");
        let two = dir.path().join("two.json");
        fs::write(&one, b"old").unwrap();
        fs::hard_link(&one, &two).unwrap();
        let w = write_atomic(&one, b"new contents").unwrap();
        assert!(w.note().unwrap().contains("2 names (hard links)"), "{w:?}");
        assert_eq!(fs::read(&two).unwrap(), b"new contents");
        assert_eq!(names(dir.path()), ["one.json", "two.json"]);
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
        let can_create = File::create(sub.join("probe")).is_ok();
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

    #[cfg(unix)]
    #[test]
    fn leftovers_of_dead_processes_are_removed_by_the_next_write_and_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        // A process id that no process has: above Linux's largest pid_max (2^22).
        let dead = dir.path().join(".state.json.clothsim-tmp.4194305");
        let live = dir
            .path()
            .join(format!(".other.json.clothsim-tmp.{}", std::process::id()));
        let unrelated = dir.path().join(".state.json.clothsim-tmp.notapid");
        for p in [&dead, &live, &unrelated] {
            fs::write(p, b"partial").unwrap();
        }
        write_atomic(&dir.path().join("state.json"), b"x").unwrap();
        assert!(!dead.exists());
        assert!(live.exists(), "our own process's file may be in flight");
        assert!(unrelated.exists(), "not a name clothsim makes");
    }

    #[test]
    fn temporary_names_carry_the_process_id() {
        assert_eq!(leftover_pid(".state.json.clothsim-tmp.123"), Some(123));
        assert_eq!(leftover_pid(".state.json.clothsim-tmp.123.4"), Some(123));
        assert_eq!(leftover_pid("state.json.clothsim-tmp.123"), None);
        assert_eq!(leftover_pid(".state.json.clothsim-tmp."), None);
        assert_eq!(leftover_pid(".state.json"), None);
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
