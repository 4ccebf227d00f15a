//! Private, verified places for a user's runs on a shared computer.
//!
//! The base directory is `$XDG_RUNTIME_DIR/admm-ta` when `XDG_RUNTIME_DIR` is a directory
//! of ours with mode 0700, else `<tmp>/admm-ta-<uid>`. It is created with mode 0700 and then
//! checked with `lstat` (never through a symlink): a directory, owned by our effective uid,
//! no permission for group or others — never trusted by its name. Run directories inside it
//! get a random name and are created exclusively (`mkdir` fails if the name exists); their
//! files are created exclusively with mode 0600 and opened with `O_NOFOLLOW`. An agent
//! reads its scenario only if it is a regular file of ours with mode 0600 whose SHA-256
//! matches the digest the launcher put on its command line.

use sha2::{Digest, Sha256};
use std::fs::{DirBuilder, File, OpenOptions};
use std::io::Read;
use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// Our effective uid.
pub fn euid() -> u32 {
    // SAFETY: geteuid cannot fail.
    unsafe { libc::geteuid() }
}

/// The user's base directory of runs and teams (created, and checked: [`check_private`]).
pub fn base_dir() -> Result<PathBuf, PrivateDirError> {
    if let Some(xdg) = std::env::var_os("XDG_RUNTIME_DIR").filter(|x| !x.is_empty()) {
        let xdg = PathBuf::from(xdg);
        if check_private(&xdg).is_ok() {
            let base = xdg.join("admm-ta");
            ensure_private_dir(&base)?;
            return Ok(base);
        }
    }
    let base = std::env::temp_dir().join(format!("admm-ta-{}", euid()));
    ensure_private_dir(&base)?;
    Ok(base)
}

/// Creates `dir` with mode 0700 unless it exists, then checks it is private.
pub fn ensure_private_dir(dir: &Path) -> Result<(), PrivateDirError> {
    match DirBuilder::new().mode(0o700).create(dir) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(source) => {
            return Err(PrivateDirError::Create {
                path: dir.to_path_buf(),
                source,
            });
        }
    }
    check_private(dir)
}

/// A directory of runs that cannot be made or is not private.
#[derive(Debug, thiserror::Error)]
pub enum PrivateDirError {
    #[error("cannot create {}", path.display())]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot inspect {}", path.display())]
    Inspect {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "refusing the run directory {}: it {why}; remove it, or set XDG_RUNTIME_DIR (or TMPDIR) to a directory only you can use",
        path.display()
    )]
    NotPrivate { path: PathBuf, why: String },
}

/// A file that is not the private file it should be.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    #[error("refusing {}: it is a symlink", path.display())]
    Symlink { path: PathBuf },
    #[error("cannot {what} {}", path.display())]
    Io {
        what: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("refusing {}: not a regular file", path.display())]
    NotAFile { path: PathBuf },
    #[error("refusing {}: owned by uid {owner}, not by this agent's (uid {ours})", path.display())]
    Owner {
        path: PathBuf,
        owner: u32,
        ours: u32,
    },
    #[error("refusing {}: mode {mode:o}, not 600", path.display())]
    Mode { path: PathBuf, mode: u32 },
    #[error(
        "refusing {}: it was replaced (digest {found}… instead of the launcher's {expected}…)",
        path.display()
    )]
    Replaced {
        path: PathBuf,
        found: String,
        expected: String,
    },
}

/// Refuses `dir` unless it is a directory (not a symlink) owned by us with no permission
/// bits for group or others; the error says what is wrong and what to do.
pub fn check_private(dir: &Path) -> Result<(), PrivateDirError> {
    let meta = std::fs::symlink_metadata(dir).map_err(|source| PrivateDirError::Inspect {
        path: dir.to_path_buf(),
        source,
    })?;
    let what = if meta.file_type().is_symlink() {
        "is a symlink (another account may have planted it)".to_string()
    } else if !meta.is_dir() {
        "is not a directory".to_string()
    } else if meta.uid() != euid() {
        format!(
            "is owned by uid {}, not by you (uid {})",
            meta.uid(),
            euid()
        )
    } else if meta.mode() & 0o077 != 0 {
        format!(
            "has mode {:o}: group or others may enter it",
            meta.mode() & 0o7777
        )
    } else {
        return Ok(());
    };
    Err(PrivateDirError::NotPrivate {
        path: dir.to_path_buf(),
        why: what,
    })
}

/// Creates a fresh private directory `<parent>/<prefix><random>` (exclusively: a name that
/// exists is never reused); returns it and its name.
pub fn create_unique_dir(parent: &Path, prefix: &str) -> std::io::Result<(PathBuf, String)> {
    loop {
        let name = format!("{prefix}{}", random_hex(6));
        let dir = parent.join(&name);
        match DirBuilder::new().mode(0o700).create(&dir) {
            Ok(()) => return Ok((dir, name)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Creates `path` exclusively (it must not exist, not even as a symlink) with mode 0600.
pub fn create_private_file(path: &Path) -> std::io::Result<File> {
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
}

/// Writes `bytes` into a new private file `path` ([`create_private_file`]).
pub fn write_private_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    create_private_file(path)?.write_all(bytes)
}

/// Reads `path` if it is a regular file of ours with mode 0600, not a symlink, and its
/// SHA-256 is `digest` (hex); the error names what is wrong.
pub fn read_verified(path: &Path, digest: &str) -> Result<Vec<u8>, VerifyError> {
    let at = || path.to_path_buf();
    let io = |what| {
        move |source| VerifyError::Io {
            what,
            path: path.to_path_buf(),
            source,
        }
    };
    let mut file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW)
        .open(path)
        .map_err(|e| match e.raw_os_error() {
            Some(libc::ELOOP) => VerifyError::Symlink { path: at() },
            _ => io("open")(e),
        })?;
    let meta = file.metadata().map_err(io("inspect"))?;
    if !meta.is_file() {
        return Err(VerifyError::NotAFile { path: at() });
    }
    if meta.uid() != euid() {
        return Err(VerifyError::Owner {
            path: at(),
            owner: meta.uid(),
            ours: euid(),
        });
    }
    if meta.mode() & 0o777 != 0o600 {
        return Err(VerifyError::Mode {
            path: at(),
            mode: meta.mode() & 0o777,
        });
    }
    let mut bytes = Vec::new();
    file.read_to_end(&mut bytes).map_err(io("read"))?;
    let found = sha256_hex(&bytes);
    if found != digest {
        return Err(VerifyError::Replaced {
            path: at(),
            found: found[..12].to_string(),
            expected: digest[..digest.len().min(12)].to_string(),
        });
    }
    Ok(bytes)
}

/// SHA-256 of `bytes`, in hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// `bytes` random bytes from the kernel, in hex (names nobody can predict).
pub fn random_hex(bytes: usize) -> String {
    let mut buf = vec![0u8; bytes];
    let mut filled = 0;
    while filled < bytes {
        // SAFETY: writing at most `bytes - filled` bytes into our buffer.
        let n = unsafe { libc::getrandom(buf[filled..].as_mut_ptr().cast(), bytes - filled, 0) };
        if n <= 0 {
            // No getrandom: time and pid still make collisions unlikely (and `mkdir` is
            // exclusive anyway).
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            let seed = sha256_hex(format!("{nanos}{}", std::process::id()).as_bytes());
            return seed[..2 * bytes].to_string();
        }
        filled += n as usize;
    }
    buf.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_directories_are_refused() {
        let dir = std::env::temp_dir().join(format!("admm-ta-pd-test-{}", random_hex(4)));
        ensure_private_dir(&dir).unwrap();
        let open = dir.join("open");
        DirBuilder::new().mode(0o777).create(&open).unwrap();
        std::fs::set_permissions(&open, std::os::unix::fs::PermissionsExt::from_mode(0o777))
            .unwrap();
        assert!(
            check_private(&open)
                .unwrap_err()
                .to_string()
                .contains("mode 777")
        );
        let link = dir.join("link");
        std::os::unix::fs::symlink(&dir, &link).unwrap();
        assert!(
            check_private(&link)
                .unwrap_err()
                .to_string()
                .contains("symlink")
        );
        let file = dir.join("file");
        write_private_file(&file, b"x").unwrap();
        assert!(write_private_file(&file, b"y").is_err(), "created twice");
        let digest = sha256_hex(b"x");
        assert_eq!(read_verified(&file, &digest).unwrap(), b"x");
        assert!(read_verified(&link.join("file"), &digest).is_ok());
        let planted = dir.join("planted");
        std::os::unix::fs::symlink(&file, &planted).unwrap();
        assert!(
            read_verified(&planted, &digest)
                .unwrap_err()
                .to_string()
                .contains("symlink")
        );
        assert!(
            read_verified(&file, &sha256_hex(b"y"))
                .unwrap_err()
                .to_string()
                .contains("replaced")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
