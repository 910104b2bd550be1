//! The page itself: [`render`] turns a [`Report`] into one HTML document with its style
//! inline, readable on a laptop and on a phone, that fetches nothing from the network.
//!
//! Every text is escaped; every link is a relative path inside the report's folder
//! ([`href`]); a path that is absolute, climbs out (`..`) or names a scheme is shown as
//! text, not linked. A short inline script marks pictures that failed to load (and counts
//! them in `body[data-broken-images]`, which the browser test reads).

use crate::{Figure, Report, Section};
use std::fmt::Write;

/// The page's style: system fonts, a readable column, pictures in a grid that becomes one
/// column on a phone.
const STYLE: &str = r#"
:root { color-scheme: light dark; --fg: #1b1f24; --bg: #ffffff; --muted: #5b636e; --line: #d9dee4; --code: #f3f5f7; --accent: #0b63c4; }
@media (prefers-color-scheme: dark) { :root { --fg: #e6e9ed; --bg: #14171a; --muted: #9aa3ad; --line: #333a42; --code: #1f2429; --accent: #6cb0ff; } }
* { box-sizing: border-box; }
body { margin: 0; font: 16px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: var(--fg); background: var(--bg); }
main { max-width: 1120px; margin: 0 auto; padding: 1rem 1.25rem 4rem; }
h1 { font-size: 1.9rem; margin: 1rem 0 0.25rem; }
h2 { font-size: 1.35rem; margin: 2.5rem 0 0.5rem; padding-top: 0.5rem; border-top: 1px solid var(--line); }
h3 { font-size: 1rem; margin: 1rem 0 0.25rem; color: var(--muted); font-weight: 600; }
a { color: var(--accent); }
nav ol { columns: 2 16rem; padding-left: 1.25rem; }
pre, code { font: 13px/1.45 ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; }
pre { background: var(--code); padding: 0.6rem 0.8rem; overflow-x: auto; border-radius: 6px; }
.scroll { overflow-x: auto; margin-bottom: 1rem; }
table { border-collapse: collapse; min-width: 60%; }
th, td { text-align: left; padding: 0.3rem 0.8rem 0.3rem 0; border-bottom: 1px solid var(--line); vertical-align: top; }
th { color: var(--muted); font-weight: 600; }
td.value { font-variant-numeric: tabular-nums; white-space: nowrap; font-weight: 600; }
.grid { display: grid; grid-template-columns: repeat(auto-fill, minmax(260px, 1fr)); gap: 0.9rem; }
figure { margin: 0; }
figure img { width: 100%; height: auto; display: block; border: 1px solid var(--line); border-radius: 4px; background: var(--code); }
figcaption { font-size: 0.85rem; color: var(--muted); margin-top: 0.25rem; }
img.broken { min-height: 3rem; outline: 2px solid #d33; }
.muted { color: var(--muted); }
ul.files { columns: 2 16rem; padding-left: 1.25rem; }
details summary { cursor: pointer; color: var(--muted); }
@media (max-width: 600px) { main { padding: 0.5rem 0.75rem 3rem; } h1 { font-size: 1.5rem; } .grid { grid-template-columns: 1fr; } }
"#;

/// Counts and marks pictures that did not load, once the page has loaded, and counts script
/// errors.
const SCRIPT: &str = r#"
window.addEventListener("error", function () {
  var n = Number(document.body.getAttribute("data-script-errors") || "0") + 1;
  document.body.setAttribute("data-script-errors", String(n));
});
window.addEventListener("load", function () {
  var broken = 0;
  document.querySelectorAll("img").forEach(function (img) {
    if (!img.complete || img.naturalWidth === 0) { broken += 1; img.classList.add("broken"); }
  });
  document.body.setAttribute("data-broken-images", String(broken));
  document.body.setAttribute("data-images", String(document.images.length));
});
"#;

/// `s` with `&`, `<`, `>`, `"` and `'` escaped, for text and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// The `href`/`src` of a path relative to the report's folder, percent-encoded (every byte
/// but ASCII letters, digits, `-._~` and the `/` separators); `None` for a path that is
/// empty, absolute, has a `..` or `.` component, a backslash or a scheme (`name:`), so that
/// the page links only to its own folder.
pub fn href(path: &str) -> Option<String> {
    if path.is_empty() || path.starts_with('/') || path.contains('\\') || path.contains(':') {
        return None;
    }
    if path.split('/').any(|c| c.is_empty() || c == ".." || c == ".") {
        return None;
    }
    let mut o = String::with_capacity(path.len());
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            o.push(char::from(b));
        } else {
            // Writing to a String cannot fail.
            let _ = write!(o, "%{b:02X}");
        }
    }
    Some(o)
}

/// An anchor id from `id`: ASCII letters, digits, `-` and `_` kept, everything else `-`.
pub fn anchor(id: &str) -> String {
    let a: String =
        id.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '-' }).collect();
    if a.is_empty() {
        "section".into()
    } else {
        a
    }
}

/// The page of `report`: a complete HTML document.
pub fn render(report: &Report) -> String {
    let mut o = String::with_capacity(16 * 1024);
    let title = escape(&report.title);
    o.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    o.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    let _ = writeln!(o, "<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<main>");
    let _ = writeln!(o, "<h1>{title}</h1>");
    if !report.intro.is_empty() {
        let _ = writeln!(o, "<p>{}</p>", escape(&report.intro));
    }
    if report.sections.len() > 1 {
        o.push_str("<nav><ol>\n");
        for s in &report.sections {
            let _ = writeln!(o, "<li><a href=\"#{}\">{}</a></li>", anchor(&s.id), escape(&s.title));
        }
        o.push_str("</ol></nav>\n");
    }
    for s in &report.sections {
        section(&mut o, s);
    }
    let _ = writeln!(o, "</main>\n<script>{SCRIPT}</script>\n</body>\n</html>");
    o
}

fn section(o: &mut String, s: &Section) {
    let _ = writeln!(o, "<section id=\"{}\">\n<h2>{}</h2>", anchor(&s.id), escape(&s.title));
    if !s.about.is_empty() {
        let _ = writeln!(o, "<p>{}</p>", escape(&s.about));
    }
    if !s.commands.is_empty() {
        let run = match s.seconds {
            Some(t) => format!("Run (in the report's folder, {t:.1} s)"),
            None => "Run (in the report's folder)".into(),
        };
        let _ = writeln!(o, "<h3>{run}</h3>\n<pre><code>{}</code></pre>", escape(&s.commands.join("\n")));
    }
    if !s.figures.is_empty() {
        figures(o, &s.figures);
    }
    if !s.pictures.is_empty() {
        o.push_str("<div class=\"grid\">\n");
        for p in &s.pictures {
            let cap = escape(&p.caption);
            match href(&p.path) {
                Some(h) => {
                    let _ = writeln!(
                        o,
                        "<figure><a href=\"{h}\"><img src=\"{h}\" alt=\"{cap}\"></a><figcaption>{cap}</figcaption></figure>"
                    );
                }
                None => {
                    let _ = writeln!(
                        o,
                        "<figure><p class=\"muted\">{} (not linked: outside the report)</p><figcaption>{cap}</figcaption></figure>",
                        escape(&p.path)
                    );
                }
            }
        }
        o.push_str("</div>\n");
    }
    if !s.files.is_empty() {
        o.push_str("<h3>Data</h3>\n<ul class=\"files\">\n");
        for f in &s.files {
            match href(f) {
                Some(h) => {
                    let _ = writeln!(o, "<li><a href=\"{h}\">{}</a></li>", escape(f));
                }
                None => {
                    let _ = writeln!(o, "<li>{} <span class=\"muted\">(not linked)</span></li>", escape(f));
                }
            }
        }
        o.push_str("</ul>\n");
    }
    if !s.log.is_empty() {
        let _ = writeln!(o, "<details><summary>What it printed</summary><pre>{}</pre></details>", escape(&s.log));
    }
    o.push_str("</section>\n");
}

fn figures(o: &mut String, figures: &[Figure]) {
    let with_ref = figures.iter().any(|f| !f.reference.is_empty());
    o.push_str("<div class=\"scroll\"><table>\n<tr><th>figure</th><th>ocellus</th>");
    if with_ref {
        o.push_str("<th>for comparison</th>");
    }
    o.push_str("</tr>\n");
    for f in figures {
        let _ = write!(o, "<tr><td>{}</td><td class=\"value\">{}</td>", escape(&f.label), escape(&f.value));
        if with_ref {
            let _ = write!(o, "<td>{}</td>", escape(&f.reference));
        }
        o.push_str("</tr>\n");
    }
    o.push_str("</table></div>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Picture, Section};
    use proptest::prelude::*;

    #[test]
    fn links_stay_inside_the_folder() {
        assert_eq!(href("stereo/disparity.png").as_deref(), Some("stereo/disparity.png"));
        assert_eq!(href("a b/c#1.png").as_deref(), Some("a%20b/c%231.png"));
        assert_eq!(href("ü.png").as_deref(), Some("%C3%BC.png"));
        for bad in
            ["", "/etc/passwd", "../x.png", "a/../../x", "./x", "a//b", "https://example.com/x.png", "c:\\x", "a\\b"]
        {
            assert_eq!(href(bad), None, "{bad}");
        }
    }

    #[test]
    fn the_page_holds_every_section_and_escapes_text() {
        let mut a = Section::new("odometry run", "How it moved <fast>");
        a.commands = vec!["ocellus odometry ground/frames --out odo".into()];
        a.figures = vec![Figure::new("drift", "0.03 %").beside("seed mode: 0.4 %")];
        a.pictures = vec![Picture::new("odo/trajectory.png", "trajectory"), Picture::new("../secret.png", "x")];
        a.files = vec!["odo/trajectory.tum".into()];
        a.log = "a < b & c".into();
        let b = Section::new("stereo", "Stereo");
        let page = render(&Report { title: "ocellus & co".into(), intro: "i".into(), sections: vec![a, b] });
        assert!(page.starts_with("<!DOCTYPE html>"));
        assert!(page.contains("<title>ocellus &amp; co</title>"));
        assert!(page.contains("id=\"odometry-run\"") && page.contains("href=\"#odometry-run\""));
        assert!(page.contains("id=\"stereo\""));
        assert!(page.contains("How it moved &lt;fast&gt;"));
        assert!(page.contains("a &lt; b &amp; c"));
        assert!(page.contains("<img src=\"odo/trajectory.png\""));
        assert!(!page.contains("src=\"../secret.png\""));
        assert!(page.contains("seed mode: 0.4 %"));
        // Self-contained: nothing fetched from elsewhere.
        for remote in ["http://", "https://", "//fonts", "<link", "src=\"http"] {
            assert!(!page.contains(remote), "{remote}");
        }
    }

    proptest! {
        /// No text, however hostile, opens a tag or ends an attribute of its own: the page
        /// has exactly the markup of the same report made of harmless text.
        #[test]
        fn no_text_escapes_its_element(t in ".{1,40}", c in ".{1,40}", p in ".{1,40}") {
            let page = |t: &str, c: &str, p: &str| {
                let mut s = Section::new(t, t);
                s.about = t.into();
                s.commands = vec![c.into()];
                s.figures = vec![Figure::new(t, c).beside(p)];
                s.pictures = vec![Picture::new(p, c)];
                s.files = vec![p.into()];
                s.log = c.into();
                render(&Report { title: t.into(), intro: c.into(), sections: vec![s, Section::new(c, p)] })
            };
            let hostile = page(&t, &c, &p);
            let harmless = page("x", "x", if href(&p).is_some() { "x" } else { "/x" });
            for ch in ['<', '>', '"'] {
                prop_assert_eq!(hostile.matches(ch).count(), harmless.matches(ch).count(), "{}", ch);
            }
        }
    }
}
