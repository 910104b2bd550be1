//! The demo's page in a real browser (issue 20): `ocellus demo --quick`, then headless
//! Chromium opens `index.html` and the test checks that every picture loaded, that the page
//! logged nothing to the console and raised no script error, that every capability's
//! section is there with figures, and that a screenshot was saved.
//!
//! Chromium is driven through its own command-line flags (`--dump-dom` after a virtual-time
//! budget, `--screenshot`), not through a DevTools-protocol crate: the two flags are all the
//! test needs, they come with the Debian package that `scripts/setup.sh` installs, and they
//! add no dependency. The page's inline script writes what it saw into attributes of `body`
//! (`data-images`, `data-broken-images`, `data-script-errors`), which `--dump-dom` shows;
//! console messages appear on Chromium's log (`--enable-logging=stderr`) as `CONSOLE` lines.
//!
//! Without Chromium the test says so and passes, unless `OCELLUS_REQUIRE_CHROMIUM=1` (set by
//! `scripts/test.sh`, which installs it) makes that a failure.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

mod common;

use common::{ocellus, run, tmpdir};
use std::process::Command;

/// The sections the demo must show, one per capability.
const SECTIONS: &[&str] =
    &["saliency", "eval", "attention", "plan", "calibration", "stereo", "odometry", "logpolar", "tracking", "retina"];

fn chromium() -> Option<String> {
    let name = std::env::var("OCELLUS_CHROMIUM").unwrap_or_else(|_| "chromium".into());
    let found = Command::new(&name).arg("--version").output().is_ok_and(|o| o.status.success());
    if !found && std::env::var("OCELLUS_REQUIRE_CHROMIUM").as_deref() == Ok("1") {
        panic!("{name} not found, and OCELLUS_REQUIRE_CHROMIUM=1: run scripts/setup.sh");
    }
    found.then_some(name)
}

/// The value of `attr="..."` on the first `<body` of `dom`.
fn body_attr(dom: &str, attr: &str) -> Option<String> {
    let body = &dom[dom.find("<body")?..];
    let body = &body[..body.find('>')?];
    let start = body.find(&format!("{attr}=\""))? + attr.len() + 2;
    Some(body[start..start + body[start..].find('"')?].to_string())
}

#[test]
fn the_demo_page_loads_whole_in_headless_chromium() {
    let out = tmpdir("demo-page");
    let printed = run(ocellus().args(["demo", "--quick", "--out"]).arg(&out));
    assert!(printed.contains("demo done"), "{printed}");
    // Every capability has its section with figures read from what its commands printed.
    for id in SECTIONS {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join(id).join("section.json")).unwrap()).unwrap();
        let figures = s["figures"].as_array().unwrap();
        assert!(!figures.is_empty(), "section {id} has no figures: {s}");
        assert!(!s["commands"].as_array().unwrap().is_empty(), "{id}");
        assert!(!s["pictures"].as_array().unwrap().is_empty(), "{id}");
    }
    let page = out.join("index.html");
    let html = std::fs::read_to_string(&page).unwrap();
    for remote in ["http://", "https://", "<link"] {
        assert!(!html.contains(remote), "the page refers to {remote}");
    }
    let Some(chrome) = chromium() else {
        eprintln!("chromium not found: the page was not opened in a browser (scripts/setup.sh installs it)");
        return;
    };
    let url = format!("file://{}", page.canonicalize().unwrap().display());
    let flags = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--hide-scrollbars"];
    let profile = out.join("chromium-profile");
    let o = Command::new(&chrome)
        .args(flags)
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(["--enable-logging=stderr", "--v=0", "--virtual-time-budget=10000", "--dump-dom"])
        .arg(&url)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dom = String::from_utf8_lossy(&o.stdout);
    let log = String::from_utf8_lossy(&o.stderr);
    let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(console.is_empty(), "the page logged to the console: {console:?}");
    let images: usize = body_attr(&dom, "data-images").expect("the page's script did not run").parse().unwrap();
    assert!(images >= 2 * SECTIONS.len(), "{images} pictures");
    assert_eq!(body_attr(&dom, "data-broken-images").as_deref(), Some("0"), "pictures failed to load");
    assert_eq!(body_attr(&dom, "data-script-errors"), None, "script errors");
    for id in SECTIONS {
        assert!(dom.contains(&format!("<section id=\"{id}\">")), "section {id} missing from the page");
    }
    // A screenshot at a laptop's width and one at a phone's.
    for (name, size) in [("page.png", "1280,2400"), ("phone.png", "390,1600")] {
        let shot = out.join(name);
        let o = Command::new(&chrome)
            .args(flags)
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(format!("--window-size={size}"))
            .arg(format!("--screenshot={}", shot.display()))
            .arg(&url)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let png = std::fs::read(&shot).unwrap();
        assert!(png.len() > 10_000 && png.starts_with(b"\x89PNG"), "{name}: {} bytes", png.len());
    }
}
