//! A `contactlab run` killed with SIGKILL in the middle leaves no truncated file under its own
//! name: `history.csv` holds complete rows only (each row is one flushed
//! write), the VTK frames and `frames.pvd` are complete XML (written to a temporary file, then
//! renamed), and `summary.json`, written last, is absent.

use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn complete_lines(path: &Path) -> usize {
    std::fs::read(path)
        .unwrap_or_default()
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

#[test]
fn a_sigkilled_run_leaves_complete_files() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("crash_run");
    let _ = std::fs::remove_dir_all(&dir);
    // balloons n = 200: 5 outer steps of about a second each on the test machine
    let mut child = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["run", "balloons", "--n", "200", "--quiet", "--out"])
        .arg(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let hist = dir.join("history.csv");
    let start = Instant::now();
    // header, iteration 0 and iteration 1 written
    while complete_lines(&hist) < 3 {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was killed"
        );
        assert!(start.elapsed() < Duration::from_secs(600));
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    let status = child.wait().unwrap();
    assert_eq!(status.signal(), Some(9), "{status:?}");

    // history.csv: complete rows, each with the header's number of fields
    let text = std::fs::read_to_string(&hist).unwrap();
    assert!(
        text.ends_with('\n'),
        "torn last row: {:?}",
        text.lines().last()
    );
    let mut r = csv::Reader::from_path(&hist).unwrap();
    let width = r.headers().unwrap().len();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert!(rows.len() >= 2, "{} rows", rows.len());
    assert!(rows.iter().all(|x| x.len() == width));
    // frames.pvd and every frame it names: complete XML
    let pvd = std::fs::read_to_string(dir.join("frames.pvd")).unwrap();
    assert!(pvd.trim_end().ends_with("</VTKFile>"), "{pvd}");
    let frames: Vec<&str> = pvd
        .split("file=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap())
        .collect();
    assert!(!frames.is_empty());
    for f in frames {
        let vtu = std::fs::read_to_string(dir.join(f)).unwrap();
        assert!(vtu.trim_end().ends_with("</VTKFile>"), "{f} is truncated");
    }
    // the run never got to its summary
    assert!(!dir.join("summary.json").exists());
}
