//! The HTML report in a real browser: headless Chromium loads a generated report with no
//! console messages at all (the page has no script, so any message is a problem: a
//! blocked outside resource, a policy violation), and its screenshot shows the embedded
//! pictures, found by their colours.
//!
//! Skipped, with a message saying so, when no Chromium is installed (Debian:
//! `apt-get install -y chromium`). Set `WEFT_CHROMIUM` to use a specific binary.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use weft_render::{
    render, Colormap, Image, LinePlot, Paint, RenderOptions, Report, ScalarPaint, ScalarRange,
    SceneMesh, Series, BODY_COLOR, PALETTE,
};

#[path = "support/mod.rs"]
mod support;

/// A colour that nothing else on the page has: the marker picture is filled with it.
const MARKER: [u8; 3] = [12, 200, 77];

fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("WEFT_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in [
            "chromium",
            "chromium-browser",
            "google-chrome",
            "google-chrome-stable",
        ] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("weft-render-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Runs headless Chromium on `page`, writing a screenshot; returns its stderr log.
fn screenshot(browser: &Path, page: &Path, shot: &Path, work: &Path) -> String {
    let profile = work.join(format!(
        "profile-{}",
        shot.file_stem().unwrap().to_string_lossy()
    ));
    std::fs::create_dir_all(&profile).unwrap();
    let log = work.join(format!(
        "{}.log",
        shot.file_stem().unwrap().to_string_lossy()
    ));
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-dev-shm-usage",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            "--enable-logging=stderr",
            "--v=0",
            "--window-size=1200,2600",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", page.display()))
        .stdin(Stdio::null())
        .stdout(File::create(work.join("stdout.log")).unwrap())
        .stderr(File::create(&log).unwrap())
        .spawn()
        .expect("chromium starts");
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        if let Some(status) = child.try_wait().expect("wait for chromium") {
            assert!(
                status.success(),
                "chromium failed: {status}\n{}",
                read(&log)
            );
            break;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish in 120 s\n{}", read(&log));
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    read(&log)
}

fn read(p: &Path) -> String {
    String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned()
}

/// Console messages in Chromium's log (`...:INFO:CONSOLE:1] "..."`, any level).
fn console_lines(log: &str) -> Vec<&str> {
    log.lines().filter(|l| l.contains(":CONSOLE")).collect()
}

/// RGB pixels of a PNG screenshot (RGB or RGBA).
fn pixels(path: &Path) -> Vec<[u8; 3]> {
    let dec = png::Decoder::new(std::io::BufReader::new(
        File::open(path).expect("screenshot"),
    ));
    let mut reader = dec.read_info().expect("PNG screenshot");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("decodes");
    let step = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected screenshot colour type {other:?}"),
    };
    buf[..info.buffer_size()]
        .chunks(step)
        .map(|p| [p[0], p[1], p[2]])
        .collect()
}

fn near(a: [u8; 3], b: [u8; 3], tol: u8) -> bool {
    (0..3).all(|k| a[k].abs_diff(b[k]) <= tol)
}

#[test]
fn report_opens_offline_without_console_messages_and_shows_its_pictures() {
    let Some(browser) = chromium() else {
        println!("skipped: no Chromium found (install it with `apt-get install -y chromium`, or set WEFT_CHROMIUM)");
        return;
    };
    let work = scratch("chromium");

    // The detector must see a broken page, or a clean log proves nothing.
    let bad = work.join("bad.html");
    std::fs::write(
        &bad,
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"></head><body><script>undefinedFn()</script></body></html>",
    )
    .unwrap();
    let log = screenshot(&browser, &bad, &work.join("bad.png"), &work);
    assert!(
        console_lines(&log).iter().any(|l| l.contains("Uncaught")),
        "Chromium's log format changed: a script error was not seen in\n{log}"
    );

    let body = support::mannequin();
    let skirt = support::skirt(40, 120);
    let error = support::fake_error_mm(&skirt);
    let scene = [
        SceneMesh::new("body", &body, Paint::Solid(BODY_COLOR)),
        SceneMesh::new(
            "skirt",
            &skirt,
            Paint::Scalars(ScalarPaint {
                values: &error,
                colormap: Colormap::Viridis,
                range: ScalarRange::Auto,
                label: "vertex error (mm)",
            }),
        ),
    ];
    let picture = render(&scene, &RenderOptions::new(500, 500)).unwrap().image;
    let plot = LinePlot {
        title: "loss".into(),
        x_label: "step".into(),
        y_label: "loss".into(),
        series: vec![Series::new(
            "vertex",
            (1..200)
                .map(|s| (f64::from(s), 1.0 / f64::from(s)))
                .collect(),
        )],
        log_y: true,
    }
    .render(700, 380)
    .unwrap();
    let mut report = Report::new("weft report test <&>");
    report
        .paragraph("A marker picture, a rendering and a plot.")
        .heading("Marker");
    report
        .image(&Image::new(300, 120, MARKER), "marker")
        .unwrap();
    report.heading("Rendering");
    report.image(&picture, "skirt over body").unwrap();
    report.heading("Plot");
    report.image(&plot, "training loss").unwrap();
    report.table(["method", "E_verts (mm)"], [["ours", "8.1"]]);
    let page = work.join("report.html");
    report.write(&page).unwrap();

    let shot = work.join("report.png");
    let log = screenshot(&browser, &page, &shot, &work);
    let console = console_lines(&log);
    assert!(
        console.is_empty(),
        "console messages:\n{}",
        console.join("\n")
    );

    let px = pixels(&shot);
    let marker = px.iter().filter(|&&p| near(p, MARKER, 6)).count();
    assert!(
        marker >= 300 * 120 * 9 / 10,
        "marker picture not shown: {marker} pixels"
    );
    let yellow = Colormap::Viridis.sample(1.0);
    let purple = Colormap::Viridis.sample(0.0);
    let mapped = px
        .iter()
        .filter(|&&p| near(p, yellow, 10) || near(p, purple, 10))
        .count();
    assert!(
        mapped > 500,
        "colour-mapped rendering not shown: {mapped} pixels"
    );
    let line = px.iter().filter(|&&p| near(p, PALETTE[0], 6)).count();
    assert!(line > 300, "plot not shown: {line} pixels");
    let _ = std::fs::remove_dir_all(&work);
}
