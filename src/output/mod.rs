//! Output writers: VTK (`.vtu` / `.pvd`) for ParaView and `meshio`, and
//! hand-written SVG figures (shapes plus an energy history plot).
//!
//! Every file is written atomically: the bytes go to `NAME.tmp` in the same
//! directory, which is then renamed over `NAME` (see [`write_atomic`]), so a
//! reader never sees a half-written file.

pub mod loglog;
pub mod plot;
pub mod run_dir;
pub mod svg;
pub mod timeseries;
pub mod vtk;

use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Path of the temporary file used by [`write_atomic`]: `NAME.tmp` next to `path`.
fn tmp_path(path: &Path) -> PathBuf {
    let mut name: OsString = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_else(|| OsString::from("output"));
    name.push(".tmp");
    path.with_file_name(name)
}

/// Writes `bytes` to `path` atomically: first to `NAME.tmp` in the same
/// directory (flushed and synced), then renamed to `NAME`.
///
/// On error the temporary file is removed (best effort).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = tmp_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_atomic_replaces_and_leaves_no_tmp() {
        let dir =
            std::env::temp_dir().join(format!("contactlab_out_atomic_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert!(!dir.join("a.txt.tmp").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
