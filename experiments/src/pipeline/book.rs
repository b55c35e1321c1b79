//! Builds the book (`book/` into `book/build/`) with mdBook, its formulas rendered to HTML by
//! KaTeX while the book is built, so that the pages need no network.
//!
//! The chapters write formulas as MathJax reads them from Markdown: `\\(...\\)` inline and
//! `\\[...\\]` displayed, with Markdown's backslash escapes inside (`\\,` for TeX's `\,`).
//! [`Math`], a preprocessor run after mdBook's own (so included files are in place), finds them
//! with mdbook-katex's scanner (which skips code spans and fenced code), undoes the Markdown
//! escapes, and replaces each formula with KaTeX's HTML (and MathML, for screen readers). The
//! stylesheet and fonts are vendored in `book/src/katex/` and linked from `book/theme/head.hbs`.
//! A formula KaTeX cannot parse stops the build with its chapter and source.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use mdbook_driver::book::{Book, BookItem};
use mdbook_katex::preprocess::{get_render_tasks, ExtraOpts, Render};
use mdbook_katex::scan::Delimiter;
use mdbook_preprocessor::{Preprocessor, PreprocessorContext};

/// Builds the book at `book_root` (the directory holding `book.toml`).
pub fn build(book_root: &Path) -> Result<()> {
    let mut book =
        mdbook_driver::MDBook::load(book_root).map_err(|e| anyhow!("loading the book: {e:#}"))?;
    book.with_preprocessor(Math);
    book.build()
        .map_err(|e| anyhow!("building the book: {e:#}"))
}

/// The preprocessor that renders the chapters' formulas with KaTeX.
pub struct Math;

impl Preprocessor for Math {
    fn name(&self) -> &str {
        "endstop-katex"
    }

    fn run(
        &self,
        _ctx: &PreprocessorContext,
        mut book: Book,
    ) -> mdbook_preprocessor::errors::Result<Book> {
        let mut failures = Vec::new();
        book.for_each_mut(|item| {
            if let BookItem::Chapter(ch) = item {
                for link in unresolved_includes(&ch.content) {
                    failures.push(format!(
                        "chapter `{}`: mdBook could not resolve `{link}` (a moved or \
                         missing file)",
                        ch.name
                    ));
                }
                match render_chapter(&ch.content) {
                    Ok(html) => ch.content = html,
                    Err(e) => failures.push(format!("chapter `{}`: {e:#}", ch.name)),
                }
            }
        });
        if !failures.is_empty() {
            return Err(anyhow!("{}", failures.join("\n")));
        }
        Ok(book)
    }
}

/// The `{{#include ...}}` links left in a chapter after mdBook's own preprocessor: it
/// replaces each link it resolves and leaves (with a logged warning only) one whose file is
/// missing, so that a moved source file would otherwise vanish from the book silently.
pub fn unresolved_includes(content: &str) -> Vec<&str> {
    let mut found = Vec::new();
    let mut rest = content;
    while let Some(start) = rest.find("{{#include") {
        let tail = &rest[start..];
        let end = tail.find("}}").map_or(tail.len(), |e| e + 2);
        found.push(&tail[..end]);
        rest = &tail[end..];
    }
    found
}

fn delimiters() -> ExtraOpts {
    ExtraOpts {
        include_src: false,
        block_delimiter: Delimiter {
            left: r"\\[".into(),
            right: r"\\]".into(),
        },
        inline_delimiter: Delimiter {
            left: r"\\(".into(),
            right: r"\\)".into(),
        },
    }
}

/// Undoes Markdown's backslash escapes: a backslash before ASCII punctuation stands for that
/// character (`\\,` is TeX's `\,`, `\\\\` is TeX's `\\`); any other backslash is kept.
pub fn unescape_markdown(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\\' {
            if let Some(&next) = chars.peek() {
                if next.is_ascii_punctuation() {
                    out.push(next);
                    chars.next();
                    continue;
                }
            }
        }
        out.push(c);
    }
    out
}

/// The TeX a chapter's Markdown would garble: a formula opened with `\(` or `\[` (Markdown
/// makes it a plain parenthesis, and the TeX shows raw), and inside a formula a lone backslash
/// before punctuation (`\,` in the source: Markdown eats the backslash, and TeX's thin space
/// becomes a comma). Code spans and fenced code are skipped. Each defect is quoted.
pub fn garbled_tex(markdown: &str) -> Vec<String> {
    let mut found = Vec::new();
    for task in get_render_tasks(markdown, "", &delimiters()) {
        match task {
            Render::Text(t) => {
                let prose = strip_code(t);
                let b = prose.as_bytes();
                for i in 0..b.len().saturating_sub(1) {
                    if b[i] == b'\\'
                        && (b[i + 1] == b'(' || b[i + 1] == b'[')
                        && (i == 0 || b[i - 1] != b'\\')
                    {
                        let end = (i + 40).min(b.len());
                        found.push(String::from_utf8_lossy(&b[i..end]).into_owned());
                    }
                }
            }
            Render::InlineTask(t) | Render::DisplayTask(t) => {
                let b = t.as_bytes();
                let mut run = 0usize;
                for &c in b {
                    if c == b'\\' {
                        run += 1;
                        continue;
                    }
                    if run % 2 == 1 && c.is_ascii_punctuation() {
                        found.push(t.to_string());
                        break;
                    }
                    run = 0;
                }
            }
        }
    }
    found
}

/// The text with code spans and fenced code removed (the scanner hands them back as text).
fn strip_code(t: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in t.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut in_span = false;
        for c in line.chars() {
            if c == '`' {
                in_span = !in_span;
            } else if !in_span {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// Renders one formula (its TeX, Markdown escapes already undone) to HTML.
pub fn render_formula(tex: &str, display: bool) -> Result<String> {
    let opts = katex::Opts::builder()
        .display_mode(display)
        .throw_on_error(true)
        .build()
        .map_err(|e| anyhow!("KaTeX options: {e}"))?;
    katex::render_with_opts(tex, &opts)
        // One line, so that Markdown keeps it inside its paragraph.
        .map(|html| html.replace('\n', " "))
        .map_err(|e| anyhow!("KaTeX cannot render `{tex}`: {e}"))
}

/// A chapter's Markdown with every formula replaced by KaTeX's HTML.
pub fn render_chapter(markdown: &str) -> Result<String> {
    let opts = delimiters();
    let mut out = String::with_capacity(markdown.len() * 2);
    let mut errors = Vec::new();
    for task in get_render_tasks(markdown, "", &opts) {
        let (tex, display) = match task {
            Render::Text(t) => {
                out.push_str(t);
                continue;
            }
            Render::InlineTask(t) => (t, false),
            Render::DisplayTask(t) => (t, true),
        };
        match render_formula(&unescape_markdown(tex), display) {
            Ok(html) => out.push_str(&html),
            Err(e) => errors.push(e.to_string()),
        }
    }
    if !errors.is_empty() {
        bail!("{}", errors.join("\n"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markdown_escapes_are_undone_before_katex() {
        assert_eq!(
            unescape_markdown(r"a \\, b_{\mathrm{im}}"),
            r"a \, b_{\mathrm{im}}"
        );
        assert_eq!(unescape_markdown(r"\\\\ \lt"), r"\\ \lt");
    }

    #[test]
    fn inline_and_display_formulas_become_katex_html() {
        let md = "Force \\\\(F_{\\mathrm{im}} \\\\, x\\\\) and\n\n\\\\[ \\frac{1}{2} \\\\]\n";
        let html = render_chapter(md).unwrap();
        assert!(!html.contains(r"\\("), "{html}");
        assert!(!html.contains(r"\\["), "{html}");
        assert_eq!(html.matches(r#"<span class="katex">"#).count(), 2, "{html}");
        assert_eq!(
            html.matches(r#"class="katex-display""#).count(),
            1,
            "{html}"
        );
        assert!(html.starts_with("Force <span"), "{html}");
    }

    #[test]
    fn an_include_mdbook_left_in_place_is_found() {
        let text = "intro\n```rust\n{{#include ../../src/gone.rs}}\n```\nend";
        assert_eq!(
            unresolved_includes(text),
            vec!["{{#include ../../src/gone.rs}}"]
        );
        assert!(unresolved_includes("no links here").is_empty());
    }

    #[test]
    fn garbled_tex_is_found_and_escaped_tex_is_not() {
        // A planted `\(` opener and an eaten thin space: both are reported.
        let bad = "near \\(e^{-T}\\) and \\\\(k = 4\\,x\\\\)";
        assert_eq!(garbled_tex(bad).len(), 2, "{:?}", garbled_tex(bad));
        let good = "near \\\\(e^{-T}\\\\) and \\\\(k = 4\\\\,x\\\\) and `\\(code\\)`";
        assert!(garbled_tex(good).is_empty(), "{:?}", garbled_tex(good));
    }

    #[test]
    fn no_chapter_garbles_its_tex() {
        let src = crate::root().join("book/src");
        let mut bad = Vec::new();
        for entry in std::fs::read_dir(&src).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "md") {
                let text = std::fs::read_to_string(&path).unwrap();
                for d in garbled_tex(&text) {
                    bad.push(format!("{}: {d}", path.display()));
                }
            }
        }
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }

    #[test]
    fn code_is_left_alone() {
        let md = "`\\\\(x\\\\)` and\n\n```text\n\\\\(y\\\\)\n```\n";
        assert_eq!(render_chapter(md).unwrap(), md);
    }

    #[test]
    fn a_formula_katex_cannot_parse_is_an_error_naming_it() {
        let err = render_chapter("bad \\\\(\\frac{1}\\\\)").unwrap_err();
        assert!(err.to_string().contains(r"\frac{1}"), "{err}");
    }
}
