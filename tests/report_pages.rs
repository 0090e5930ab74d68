//! The demo's pages and text as a person reads them (issue 16, item 4): the motor and cloth
//! reports show the error beneath and zoomed, say why a signature disagrees, flag fits on
//! their bounds without a ±, print no unit "1", keep one length unit on the cloth page, and
//! no line of the demo's text passes 99 characters.

#![allow(clippy::unwrap_used, clippy::expect_used)] // in test helpers, a panic is a test failure

use std::path::Path;
use std::process::Command;

/// A fresh directory under the system's temporary directory.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("modelgap-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every parameter text in `text` that says it is on a bound: none may carry a ±.
fn bound_params(text: &str) -> Vec<String> {
    text.split([',', ';', '\n'])
        .filter(|p| p.contains("(at its "))
        .map(|p| p.trim().to_owned())
        .collect()
}

#[test]
fn the_demo_pages_and_text_read_without_the_terminal() {
    let dir = temp_dir("report-pages");
    let report = dir.join("report");
    let out = Command::new(env!("CARGO_BIN_EXE_modelgap"))
        .args(["demo", "--report", report.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();

    for line in text.lines() {
        assert!(
            line.chars().count() < 100,
            "{} chars: {line}",
            line.chars().count()
        );
    }
    // The fits that end on a bound say so, with no ±.
    let bound = bound_params(&text);
    assert!(
        bound
            .iter()
            .any(|p| p.starts_with("beta = 5e-5 N m s/rad (at its upper bound")),
        "{bound:?}"
    );
    assert!(bound.iter().all(|p| !p.contains('±')), "{bound:?}");
    // Every signature tag carries its reason.
    for line in text.lines().filter(|l| l.contains("[signature ")) {
        assert!(
            line.contains("] measured ") || line.contains("] no output"),
            "{line}"
        );
    }
    assert!(
        !text.contains(" 1;") && !text.contains(" 1,"),
        "a unit 1 in:\n{text}"
    );

    let motor = std::fs::read_to_string(report.join("report.html")).unwrap();
    // The error beneath each measured-against-model plot, and a zoom.
    assert!(
        motor.contains("measured − model (A)"),
        "no residual strip for i"
    );
    assert!(
        motor.contains("measured − model (rad/s)"),
        "no residual strip for omega"
    );
    assert_eq!(
        motor.matches("The bottom panel zooms into").count(),
        2,
        "a zoom per output"
    );
    // The chosen effect's qualitative check, with its reason, in the summary.
    assert!(
        motor.contains("The model&#39;s qualitative diagnosis") && motor.contains("which is"),
        "no reason for the signature check"
    );
    let bound = bound_params(&motor);
    assert!(
        !bound.is_empty() && bound.iter().all(|p| !p.contains('±')),
        "{bound:?}"
    );

    let cloth = std::fs::read_to_string(Path::new(&report).join("cloth/report.html")).unwrap();
    for unit_one in [" 1<", " 1,", " 1;", " 1)"] {
        assert!(!cloth.contains(unit_one), "unit 1 printed: `{unit_one}`");
    }
    // One length unit on the cloth page: millimetres, in the plots as in the table.
    assert!(cloth.contains("value (mm)") && cloth.contains("residual (mm)"));
    for metres in ["value (m)", "residual (m)", "(m)<", " m after", " m before"] {
        assert!(
            !cloth.contains(metres),
            "metres on the cloth page: `{metres}`"
        );
    }
    assert!(cloth.contains("measured − model (mm)") && cloth.contains("zoom on "));
    let _ = std::fs::remove_dir_all(&dir);
}
