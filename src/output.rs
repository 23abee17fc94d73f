//! Every file grainline writes goes through this module (docs/formats.md, "How files are
//! written"):
//!
//! - **Checked before any work.** [`OutputPlan::check`] refuses an output that is a directory,
//!   a FIFO, a device, a socket or a symbolic link, two outputs on one file, and an output on
//!   one of the run's inputs. Files are compared by canonical path (for an output that does not
//!   exist yet: its nearest existing ancestor, canonicalized, and the rest of the path) and, when
//!   both exist, by (device, inode), so a hard link or `./a/../x.svg` is the same file.
//! - **Staged, then persisted together.** [`Staged::add`] writes an output into a temporary file
//!   in the target's directory, created exclusively (`O_EXCL`) with an unpredictable name by the
//!   `tempfile` crate, and fsyncs it; [`Staged::commit`] renames every temporary over its target
//!   (and fsyncs the directory) only once all of them are written. A run that fails part-way
//!   leaves its old outputs untouched and no temporary behind.
//! - **Interrupted runs leave nothing behind.** Every live temporary is registered here;
//!   [`remove_temporaries`] deletes them (the binary calls it from its SIGINT / SIGTERM / SIGHUP
//!   handler, since destructors do not run when a signal ends the process). A signal during a
//!   commit's renames waits for them: the whole new set is in place, then the process ends.
//! - **A testing aid.** [`RENAME_PAUSE_ENV`] makes a commit pause between its renames, so the
//!   tests can send a signal during them.

use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use crate::{Error, Result};

/// The temporaries alive in this process, whether new ones are still allowed, and how many
/// outputs were renamed into place.
struct Registry {
    paths: Vec<PathBuf>,
    closed: bool,
    renamed: usize,
}

static REGISTRY: Mutex<Registry> =
    Mutex::new(Registry { paths: Vec::new(), closed: false, renamed: 0 });

/// Set by [`remove_temporaries`] before it waits for a commit's renames.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// The environment variable that makes [`Staged::commit`] pause this many milliseconds (at
/// most 10 000) between two renames: a testing aid (docs/formats.md, "How files are
/// written"), so a test can send a signal while a set of outputs is half renamed. Read by the
/// commit alone; unset, or not a whole number, no pause.
pub const RENAME_PAUSE_ENV: &str = "GRAINLINE_TEST_RENAME_PAUSE_MS";

/// The pause [`RENAME_PAUSE_ENV`] asks for.
fn rename_pause() -> Option<Duration> {
    let ms: u64 = std::env::var(RENAME_PAUSE_ENV).ok()?.trim().parse().ok()?;
    Some(Duration::from_millis(ms.min(10_000)))
}

fn registry() -> std::sync::MutexGuard<'static, Registry> {
    REGISTRY.lock().unwrap_or_else(|e| e.into_inner())
}

/// Deletes every temporary file this process has created and not yet persisted or removed, and
/// refuses new ones from then on (a later [`Staged::add`] fails). Returns how many were deleted.
/// Meant for a signal handler running on its own thread (it takes a lock, so not for a
/// handler in signal context); the caller then exits.
///
/// It first marks the process interrupted ([`interrupted`]), then takes the lock a commit holds
/// during its renames: a signal during them waits until the whole new set is in place.
pub fn remove_temporaries() -> usize {
    INTERRUPTED.store(true, Ordering::SeqCst);
    let mut r = registry();
    r.closed = true;
    let mut n = 0;
    for p in r.paths.drain(..) {
        if std::fs::remove_file(&p).is_ok() {
            n += 1;
        }
    }
    n
}

/// Whether [`remove_temporaries`] was called: the process is being ended by a signal. The
/// binary does not exit on its own once this is set, so that the signal's exit status is the
/// one the process ends with, also when the signal came during the last renames.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// How many outputs this process has renamed into place.
pub fn renamed() -> usize {
    registry().renamed
}

/// The temporaries currently alive (for tests and diagnostics).
pub fn live_temporaries() -> Vec<PathBuf> {
    registry().paths.clone()
}

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io { path: path.to_path_buf(), source }
}

fn refuse(path: &Path, message: impl Into<String>) -> Error {
    Error::Io { path: path.to_path_buf(), source: std::io::Error::other(message.into()) }
}

/// Checks that `path` can be an output: absent, or a regular file. Directories, FIFOs,
/// devices and sockets are refused, and so are symbolic links (grainline never writes through
/// a link: give the link's target instead).
pub fn check_output_target(path: &Path) -> Result<()> {
    if path.file_name().is_none() {
        return Err(refuse(path, "is not a file name"));
    }
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_error(path, e)),
    };
    let ft = meta.file_type();
    if ft.is_file() {
        return Ok(());
    }
    if ft.is_symlink() {
        let to =
            std::fs::read_link(path).map(|t| format!(" (to {})", t.display())).unwrap_or_default();
        return Err(refuse(
            path,
            format!(
                "is a symbolic link{to}; grainline does not write through links: give the \
                 target's path"
            ),
        ));
    }
    let kind = if ft.is_dir() { "a directory" } else { special_kind(&ft) };
    Err(refuse(path, format!("is {kind}, not a regular file; an output must be a regular file")))
}

/// Checks that the input `path` is a regular file (links followed), from its metadata and
/// before it is opened: opening a FIFO blocks until something writes into it, and a device may
/// never end. Directories, FIFOs, devices and sockets are refused, naming the file.
pub fn check_input_file(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    let ft = meta.file_type();
    if ft.is_file() {
        return Ok(());
    }
    let kind = if ft.is_dir() { "a directory" } else { special_kind(&ft) };
    Err(refuse(path, format!("is {kind}, not a regular file; an input must be a regular file")))
}

/// Reads the input `path` whole, refusing it unread when it is not a regular file
/// ([`check_input_file`]: a FIFO would block) or its size is over `max` bytes (from its
/// metadata, before anything is read; the read itself stops at `max` + 1 bytes, should the
/// file grow meanwhile). `what` names the budget in the message (e.g. `a scene file`).
pub fn read_bounded(path: &Path, max: u64, what: &str) -> Result<Vec<u8>> {
    use std::io::Read;
    check_input_file(path)?;
    let too_big = |size: u64| {
        refuse(
            path,
            format!(
                "is {size} bytes, over the {max} bytes {what} may have (docs/scene.md, \
                 \"Limits\")"
            ),
        )
    };
    let size = std::fs::metadata(path).map_err(|e| io_error(path, e))?.len();
    if size > max {
        return Err(too_big(size));
    }
    let f = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut bytes = Vec::with_capacity(size as usize);
    f.take(max + 1).read_to_end(&mut bytes).map_err(|e| io_error(path, e))?;
    if bytes.len() as u64 > max {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`read_bounded`] as UTF-8 text; invalid UTF-8 is refused naming the file and the line.
pub fn read_bounded_text(path: &Path, max: u64, what: &str) -> Result<String> {
    let bytes = read_bounded(path, max, what)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        Error::Parse { path: path.to_path_buf(), line, message: "is not UTF-8 text".into() }
    })
}

#[cfg(unix)]
fn special_kind(ft: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_fifo() {
        "a FIFO"
    } else if ft.is_char_device() {
        "a character device"
    } else if ft.is_block_device() {
        "a block device"
    } else if ft.is_socket() {
        "a socket"
    } else {
        "a special file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "a special file"
}

/// The identity of a file for comparison: its canonical path (the nearest existing ancestor
/// canonicalized, the rest appended with `.` and `..` resolved by hand: a directory that does
/// not exist yet cannot be a link) and, when the file exists, its (device, inode).
#[derive(Clone, Debug)]
struct FileId {
    canonical: PathBuf,
    inode: Option<(u64, u64)>,
}

impl FileId {
    fn of(path: &Path) -> Result<FileId> {
        let abs = if path.is_absolute() {
            path.to_path_buf()
        } else {
            std::env::current_dir().map_err(|e| io_error(path, e))?.join(path)
        };
        let canonical = canonical_prefix(&abs);
        let inode = std::fs::metadata(path).ok().and_then(|m| inode_of(&m));
        Ok(FileId { canonical, inode })
    }

    fn same(&self, other: &FileId) -> bool {
        self.canonical == other.canonical
            || matches!((self.inode, other.inode), (Some(a), Some(b)) if a == b)
    }
}

#[cfg(unix)]
fn inode_of(m: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode_of(_: &std::fs::Metadata) -> Option<(u64, u64)> {
    None
}

/// `abs` with its longest existing prefix canonicalized and the rest normalized lexically.
fn canonical_prefix(abs: &Path) -> PathBuf {
    let mut rest: Vec<Component> = Vec::new();
    let mut head = abs;
    loop {
        if let Ok(c) = std::fs::canonicalize(head) {
            let mut out = c;
            for comp in rest.iter().rev() {
                match comp {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    other => out.push(other.as_os_str()),
                }
            }
            return out;
        }
        match (head.parent(), head.components().next_back()) {
            (Some(parent), Some(last)) => {
                rest.push(last);
                head = parent;
            }
            _ => return abs.to_path_buf(),
        }
    }
}

/// The files a command will write and the files it reads, checked together before any work.
#[derive(Clone, Debug, Default)]
pub struct OutputPlan {
    outputs: Vec<(String, PathBuf)>,
    inputs: Vec<(String, PathBuf)>,
}

impl OutputPlan {
    /// No files yet.
    pub fn new() -> Self {
        OutputPlan::default()
    }

    /// An output, named in messages by `what` (its scene key or its flag, e.g.
    /// `toolpaths.gcode` or `--out`).
    pub fn output(&mut self, what: impl Into<String>, path: impl Into<PathBuf>) -> &mut Self {
        self.outputs.push((what.into(), path.into()));
        self
    }

    /// An input the outputs must not overwrite (the scene file, the mesh, a `--field` file, …).
    pub fn input(&mut self, what: impl Into<String>, path: impl Into<PathBuf>) -> &mut Self {
        self.inputs.push((what.into(), path.into()));
        self
    }

    /// The outputs, in the order given.
    pub fn outputs(&self) -> impl Iterator<Item = &Path> {
        self.outputs.iter().map(|(_, p)| p.as_path())
    }

    /// Refuses an input that is not a regular file ([`check_input_file`]) or cannot be opened,
    /// a non-regular or symlinked output
    /// ([`check_output_target`]), two outputs on one file, and an output on an input, naming
    /// the keys and the path.
    pub fn check(&self) -> Result<()> {
        for (what, p) in &self.inputs {
            // Checked before it is opened: opening a FIFO would block.
            if let Err(e) = check_input_file(p)
                .and_then(|_| std::fs::File::open(p).map(drop).map_err(|e| io_error(p, e)))
            {
                let why = match e {
                    Error::Io { source, .. } => source.to_string(),
                    e => e.to_string(),
                };
                return Err(refuse(p, format!("{what}: {why}")));
            }
        }
        for (what, p) in &self.outputs {
            check_output_target(p).map_err(|e| match e {
                Error::Io { path, source } => refuse(&path, format!("{what}: {source}")),
                e => e,
            })?;
        }
        let out_ids: Vec<FileId> =
            self.outputs.iter().map(|(_, p)| FileId::of(p)).collect::<Result<_>>()?;
        for (i, a) in out_ids.iter().enumerate() {
            for (j, b) in out_ids.iter().enumerate().take(i) {
                if a.same(b) {
                    return Err(refuse(
                        &self.outputs[i].1,
                        format!(
                            "{} and {} are the same file; give each output its own path",
                            self.outputs[j].0, self.outputs[i].0
                        ),
                    ));
                }
            }
        }
        for (what_in, p_in) in &self.inputs {
            let id = FileId::of(p_in)?;
            for (k, o) in out_ids.iter().enumerate() {
                if o.same(&id) {
                    return Err(refuse(
                        &self.outputs[k].1,
                        format!(
                            "{} would overwrite the input {what_in} ({}); write the output \
                             elsewhere",
                            self.outputs[k].0,
                            p_in.display()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A temporary file, registered so that [`remove_temporaries`] can delete it.
struct Pending {
    target: PathBuf,
    temp: Option<tempfile::TempPath>,
}

impl Drop for Pending {
    fn drop(&mut self) {
        if let Some(t) = self.temp.take() {
            let mut r = registry();
            let p: &Path = t.as_ref();
            r.paths.retain(|q| q != p);
            drop(t); // deletes the file
        }
    }
}

/// Outputs written into temporaries beside their targets, persisted together by
/// [`Staged::commit`]. Dropping a `Staged` without committing deletes the temporaries.
#[derive(Default)]
pub struct Staged {
    pending: Vec<Pending>,
    /// Directories [`Staged::add`] created, deepest first: removed again (when empty) if the
    /// outputs are dropped without a commit, so that a failed run leaves nothing behind.
    created: Vec<PathBuf>,
}

impl Drop for Staged {
    fn drop(&mut self) {
        // The temporaries first (each `Pending` deletes its own), then the directories.
        self.pending.clear();
        for d in self.created.drain(..) {
            let _ = std::fs::remove_dir(&d);
        }
    }
}

impl Staged {
    /// Nothing staged yet.
    pub fn new() -> Self {
        Staged::default()
    }

    /// Writes `bytes` into a new temporary file in `path`'s directory (created, with its
    /// parents, if missing), exclusively created with an unpredictable name, and fsyncs it.
    /// `path` itself is not touched until [`Staged::commit`].
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        check_output_target(path)?;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let mut missing = Vec::new();
        let mut d = dir.as_path();
        while !d.as_os_str().is_empty() && std::fs::symlink_metadata(d).is_err() {
            missing.push(d.to_path_buf());
            d = d.parent().unwrap_or(Path::new(""));
        }
        std::fs::create_dir_all(&dir).map_err(|e| io_error(&dir, e))?;
        // Deepest first, after those of earlier outputs (which may hold these).
        self.created.splice(0..0, missing);
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            // What `File::create` would give (0666 less the umask), not tempfile's 0600.
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        // Created and registered under the lock: a signal handler sees every temporary.
        let file = {
            let mut r = registry();
            if r.closed {
                return Err(refuse(path, "interrupted: no new output is written"));
            }
            let file = builder.tempfile_in(&dir).map_err(|e| io_error(path, e))?;
            r.paths.push(file.path().to_path_buf());
            file
        };
        let (mut f, temp) = file.into_parts();
        let pending = Pending { target: path.to_path_buf(), temp: Some(temp) };
        f.write_all(bytes).and_then(|_| f.sync_all()).map_err(|e| io_error(path, e))?;
        drop(f);
        self.pending.push(pending);
        Ok(())
    }

    /// The targets staged so far.
    pub fn targets(&self) -> impl Iterator<Item = &Path> {
        self.pending.iter().map(|p| p.target.as_path())
    }

    /// Renames every temporary over its target, in the order staged, then fsyncs the
    /// directories. Returns the targets.
    ///
    /// Every target is checked again before the first rename, so a target that became a
    /// directory or a link meanwhile fails the commit with nothing renamed. The renames run
    /// under the registry's lock: a signal handler's [`remove_temporaries`] waits for them,
    /// so a SIGINT / SIGTERM / SIGHUP leaves either the old set of outputs (it came first:
    /// the commit is refused) or the whole new one (it came during the renames), never a mix.
    pub fn commit(mut self) -> Result<Vec<PathBuf>> {
        for p in &self.pending {
            check_output_target(&p.target)?;
        }
        let mut done = Vec::new();
        let mut r = registry();
        if r.closed && !self.pending.is_empty() {
            return Err(refuse(&self.pending[0].target, "interrupted: no output was replaced"));
        }
        let pause = rename_pause();
        for (i, mut p) in std::mem::take(&mut self.pending).into_iter().enumerate() {
            if let (true, Some(d)) = (i > 0, pause) {
                std::thread::sleep(d);
            }
            let temp = p.temp.take().expect("a pending output holds its temporary");
            let tp: PathBuf = temp.to_path_buf();
            let result = temp.persist(&p.target);
            r.paths.retain(|q| q != &tp);
            r.renamed += usize::from(result.is_ok());
            if let Err(e) = result {
                drop(r);
                drop(e.path); // deletes the temporary
                return Err(io_error(&p.target, e.error));
            }
            done.push(p.target.clone());
        }
        drop(r);
        self.created.clear();
        #[cfg(unix)]
        {
            let mut dirs: Vec<PathBuf> = done
                .iter()
                .map(|t| match t.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                    _ => PathBuf::from("."),
                })
                .collect();
            dirs.sort();
            dirs.dedup();
            for d in dirs {
                // The rename reaches the disk (best effort: not every file system allows it).
                if let Ok(f) = std::fs::File::open(&d) {
                    let _ = f.sync_all();
                }
            }
        }
        Ok(done)
    }
}

/// Writes `bytes` to `path` atomically: a temporary file in the same directory (exclusive,
/// unpredictable name), fsync, rename. Refuses non-regular and symlinked targets.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut s = Staged::new();
    s.add(path, bytes)?;
    s.commit().map(|_| ())
}

/// `value` as pretty JSON ending in a newline.
pub fn json_pretty<T: serde::Serialize>(value: &T) -> Result<Vec<u8>> {
    let mut bytes = serde_json::to_vec_pretty(value)
        .map_err(|e| Error::Numerical { stage: "JSON output", message: e.to_string() })?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// `value` as compact JSON (one line) ending in a newline.
pub fn json_compact<T: serde::Serialize>(value: &T) -> Result<Vec<u8>> {
    let mut bytes = serde_json::to_vec(value)
        .map_err(|e| Error::Numerical { stage: "JSON output", message: e.to_string() })?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// Serializes `value` as pretty JSON (ending in a newline) and writes it atomically.
pub fn write_json_atomic<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    write_atomic(path, &json_pretty(value)?)
}

/// Serializes `value` as compact JSON (one line, ending in a newline) and writes it atomically:
/// for large per-vertex files, where pretty-printing would triple the size.
pub fn write_json_compact_atomic<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    write_atomic(path, &json_compact(value)?)
}

/// Reads a JSON file into `T`, with errors that name the file and line.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read(path).map_err(|source| io_error(path, source))?;
    serde_json::from_slice(&text).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("grainline-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn failed_write_keeps_the_old_file() {
        let d = dir("keep");
        let p = d.join("a.txt");
        write_atomic(&p, b"good").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"good");
        assert!(write_atomic(&d, b"bad").is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"good");
        assert_eq!(entries(&d), ["a.txt"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn staged_outputs_appear_only_on_commit_and_vanish_on_drop() {
        let d = dir("staged");
        std::fs::write(d.join("a.txt"), b"old a").unwrap();
        let mut s = Staged::new();
        s.add(&d.join("a.txt"), b"new a").unwrap();
        s.add(&d.join("sub/b.txt"), b"new b").unwrap();
        // Before the commit: the old file untouched, b absent, two hidden temporaries.
        assert_eq!(std::fs::read(d.join("a.txt")).unwrap(), b"old a");
        assert!(!d.join("sub/b.txt").exists());
        let names = entries(&d);
        assert!(names.iter().any(|n| n.starts_with(".a.txt.") && n.ends_with(".tmp")), "{names:?}");
        drop(s);
        // Nothing left: the temporaries and the directory made for them are gone.
        assert_eq!(entries(&d), ["a.txt"]);
        let mut s = Staged::new();
        s.add(&d.join("a.txt"), b"new a").unwrap();
        s.add(&d.join("sub/b.txt"), b"new b").unwrap();
        assert_eq!(s.commit().unwrap().len(), 2);
        assert_eq!(std::fs::read(d.join("a.txt")).unwrap(), b"new a");
        assert_eq!(std::fs::read(d.join("sub/b.txt")).unwrap(), b"new b");
        assert_eq!(entries(&d), ["a.txt", "sub"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn canonical_prefix_resolves_dots_past_missing_directories() {
        let d = dir("canon");
        let real = std::fs::canonicalize(&d).unwrap();
        assert_eq!(canonical_prefix(&d.join("new/../x.svg")), real.join("x.svg"));
        assert_eq!(canonical_prefix(&d.join("./a/./b.svg")), real.join("a/b.svg"));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
