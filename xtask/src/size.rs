//! The `size` step of `cargo xtask test`: no source file longer than [`MAX_FILE_LINES`] lines
//! before its trailing test module, and no function body longer than [`MAX_FN_LINES`] lines.
//!
//! Long files and functions are where a newcomer gets lost; the limits keep every module and
//! function readable in one sitting. The check reads the `.rs` files under [`ROOTS`] with a small
//! lexer that skips comments, strings (raw and byte strings included) and character literals, so
//! braces inside them don't count:
//!
//! * a file's length is its number of lines, or, when it ends with a `#[cfg(test)] mod NAME { .. }`
//!   module, the number of lines before that module;
//! * a function's length runs from the line of its body's `{` to the line of the matching `}`,
//!   both included. Functions inside functions, `impl` blocks and test modules count alike.
//!
//! Each offender is printed as `path:line` (the path relative to the workspace root), with what
//! is too long and by how much, and the step fails while any is left.

use std::path::{Path, PathBuf};

/// Most lines a file may have before its trailing `#[cfg(test)]` module.
pub const MAX_FILE_LINES: usize = 800;

/// Most lines a function body may have, from its `{` line to its `}` line.
pub const MAX_FN_LINES: usize = 120;

/// The source trees checked, relative to the workspace root; `*` stands for every folder.
pub const ROOTS: &[&str] = &["crates/*/src", "xtask/src", "tests", "benches"];

/// One file or function over its limit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Offender {
    /// The file, relative to the workspace root, with `/` separators.
    pub path: String,
    /// The 1-based line: 1 for a file, the line of `fn` for a function.
    pub line: usize,
    /// `None` for a file; the function's name otherwise.
    pub function: Option<String>,
    /// The measured length, in lines.
    pub lines: usize,
}

impl Offender {
    /// The limit that this offender exceeds.
    #[must_use]
    pub fn limit(&self) -> usize {
        if self.function.is_some() {
            MAX_FN_LINES
        } else {
            MAX_FILE_LINES
        }
    }
}

impl std::fmt::Display for Offender {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.function {
            Some(name) => write!(
                f,
                "{}:{}: fn {name} has a {}-line body (limit {})",
                self.path,
                self.line,
                self.lines,
                self.limit()
            ),
            None => write!(
                f,
                "{}:{}: {} lines before its tests (limit {})",
                self.path,
                self.line,
                self.lines,
                self.limit()
            ),
        }
    }
}

/// Runs the check on the workspace at `root` and prints every offender.
///
/// # Errors
/// The number of offenders and the first of them when there is any, or a file that can't be
/// read.
pub fn check(root: &Path) -> Result<(), String> {
    let mut offenders = Vec::new();
    let files = source_files(root)?;
    for file in &files {
        let text = std::fs::read_to_string(file)
            .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
        let rel = file
            .strip_prefix(root)
            .unwrap_or(file)
            .to_string_lossy()
            .replace('\\', "/");
        offenders.extend(offenders_in(&rel, &text));
    }
    println!(
        "size: {} files under {} checked: at most {MAX_FILE_LINES} lines per file before its \
         trailing test module, at most {MAX_FN_LINES} lines per function body",
        files.len(),
        ROOTS.join(", ")
    );
    if offenders.is_empty() {
        return Ok(());
    }
    let mut crates: Vec<&str> = offenders.iter().map(|o| area(&o.path)).collect();
    crates.dedup();
    println!(
        "size: {} over the limits, in {}:",
        offenders.len(),
        crates.join(", ")
    );
    for o in &offenders {
        println!("  {o}");
    }
    Err(format!(
        "{} file(s) or function(s) over the size limits (first: {})",
        offenders.len(),
        offenders[0]
    ))
}

/// The crate or top-level folder `path` belongs to (`crates/cli`, `xtask`, `tests`).
fn area(path: &str) -> &str {
    let mut parts = path.splitn(3, '/');
    let first = parts.next().unwrap_or(path);
    if first == "crates" {
        let second = parts.next().unwrap_or("");
        &path[..first.len() + 1 + second.len()]
    } else {
        first
    }
}

/// Every `.rs` file under [`ROOTS`] in `root`, sorted.
fn source_files(root: &Path) -> Result<Vec<PathBuf>, String> {
    let mut dirs = Vec::new();
    for pattern in ROOTS {
        match pattern.split_once("/*/") {
            Some((parent, child)) => {
                let parent = root.join(parent);
                let entries = std::fs::read_dir(&parent)
                    .map_err(|e| format!("cannot list {}: {e}", parent.display()))?;
                for entry in entries.flatten() {
                    let dir = entry.path().join(child);
                    if dir.is_dir() {
                        dirs.push(dir);
                    }
                }
            }
            None => dirs.push(root.join(pattern)),
        }
    }
    let mut files = Vec::new();
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name();
            if path.is_dir() {
                if name != "target" && !name.to_string_lossy().starts_with('.') {
                    dirs.push(path);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    files.sort();
    Ok(files)
}

/// The offenders in one file, `path` being its name in the report.
#[must_use]
pub fn offenders_in(path: &str, text: &str) -> Vec<Offender> {
    let tokens = tokens(text);
    let mut out = Vec::new();
    let lines = lines_before_tests(text, &tokens);
    if lines > MAX_FILE_LINES {
        out.push(Offender {
            path: path.to_owned(),
            line: 1,
            function: None,
            lines,
        });
    }
    for (name, line, body) in functions(&tokens) {
        if body > MAX_FN_LINES {
            out.push(Offender {
                path: path.to_owned(),
                line,
                function: Some(name.to_owned()),
                lines: body,
            });
        }
    }
    out
}

/// A token that matters for the check: a word (identifier, keyword or number) or one
/// punctuation character, with its 1-based line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Tok<'a> {
    Word(&'a str),
    Punct(char),
}

#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    tok: Tok<'a>,
    line: usize,
}

/// The words and punctuation of `src`, without comments, strings and character literals.
fn tokens(src: &str) -> Vec<Token<'_>> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    // Skips from `i` to just past the byte `end`, counting lines; backslash escapes when `esc`.
    let skip_to = |i: &mut usize, line: &mut usize, end: u8, esc: bool| {
        while *i < b.len() && b[*i] != end {
            if esc && b[*i] == b'\\' {
                *i += 1;
            }
            if *i < b.len() && b[*i] == b'\n' {
                *line += 1;
            }
            *i += 1;
        }
        *i += 1;
    };
    while i < b.len() {
        let c = b[i];
        match c {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let mut depth = 0;
                while i < b.len() {
                    if b[i..].starts_with(b"/*") {
                        depth += 1;
                        i += 2;
                    } else if b[i..].starts_with(b"*/") {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        line += usize::from(b[i] == b'\n');
                        i += 1;
                    }
                }
            }
            b'"' => {
                i += 1;
                skip_to(&mut i, &mut line, b'"', true);
            }
            b'\'' => {
                // A character literal ('x', '\n', '\u{..}', 'é') or a lifetime ('a).
                let len = src[i + 1..].chars().next().map_or(1, char::len_utf8);
                if b.get(i + 1) == Some(&b'\\') {
                    i += 1;
                    skip_to(&mut i, &mut line, b'\'', true);
                } else if b.get(i + 1 + len) == Some(&b'\'') {
                    i += len + 2;
                } else {
                    i += 1;
                }
            }
            c if c.is_ascii_alphanumeric() || c == b'_' || c >= 0x80 => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_' || b[i] >= 0x80)
                {
                    i += 1;
                }
                let word = &src[start..i];
                let hashes = b[i..].iter().take_while(|&&h| h == b'#').count();
                if matches!(word, "r" | "br" | "cr") && b.get(i + hashes) == Some(&b'"') {
                    // A raw string: ends at `"` followed by as many `#`.
                    let close: Vec<u8> = std::iter::once(b'"')
                        .chain(std::iter::repeat_n(b'#', hashes))
                        .collect();
                    i += hashes + 1;
                    while i < b.len() && !b[i..].starts_with(&close) {
                        line += usize::from(b[i] == b'\n');
                        i += 1;
                    }
                    i += close.len();
                } else if matches!(word, "b" | "c") && matches!(b.get(i), Some(b'"' | b'\'')) {
                    // A byte or C string, or a byte literal: lexed as the quote that follows.
                } else {
                    out.push(Token {
                        tok: Tok::Word(word),
                        line,
                    });
                }
            }
            c if c.is_ascii_whitespace() => i += 1,
            c => {
                out.push(Token {
                    tok: Tok::Punct(char::from(c)),
                    line,
                });
                i += 1;
            }
        }
    }
    out
}

/// The index of the token that closes the bracket opened at `open` (`{`, `(` or `[`), if any.
fn matching(tokens: &[Token<'_>], open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (k, t) in tokens.iter().enumerate().skip(open) {
        match t.tok {
            Tok::Punct('{' | '(' | '[') => depth += 1,
            Tok::Punct('}' | ')' | ']') => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    return Some(k);
                }
            }
            _ => {}
        }
    }
    None
}

/// Every function with a body: its name, the line of `fn`, and its body's length in lines.
fn functions<'a>(tokens: &[Token<'a>]) -> Vec<(&'a str, usize, usize)> {
    let mut out = Vec::new();
    for (k, t) in tokens.iter().enumerate() {
        let (Tok::Word("fn"), Some(Tok::Word(name))) = (t.tok, tokens.get(k + 1).map(|n| n.tok))
        else {
            continue;
        };
        // The body's `{`: the first `{` outside brackets after the name (`;` ends a declaration
        // without a body; `[T; N]` and `(..)` are skipped whole).
        let mut j = k + 2;
        let open = loop {
            match tokens.get(j).map(|t| t.tok) {
                Some(Tok::Punct('{')) => break Some(j),
                Some(Tok::Punct(';')) | None => break None,
                Some(Tok::Punct('(' | '[')) => j = matching(tokens, j).unwrap_or(tokens.len()),
                _ => {}
            }
            j += 1;
        };
        if let Some(open) = open {
            if let Some(close) = matching(tokens, open) {
                out.push((name, t.line, tokens[close].line - tokens[open].line + 1));
            }
        }
    }
    out
}

/// The file's length for the limit: the lines before a trailing `#[cfg(test)] mod NAME { .. }`,
/// or all its lines.
fn lines_before_tests(text: &str, tokens: &[Token<'_>]) -> usize {
    let all = text.lines().count();
    let attr = [
        Tok::Punct('#'),
        Tok::Punct('['),
        Tok::Word("cfg"),
        Tok::Punct('('),
        Tok::Word("test"),
        Tok::Punct(')'),
        Tok::Punct(']'),
    ];
    let mut depth = 0usize;
    for (k, t) in tokens.iter().enumerate() {
        match t.tok {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => depth = depth.saturating_sub(1),
            _ => {}
        }
        if depth != 0 || tokens.len() < k + attr.len() + 3 {
            continue;
        }
        let at = &tokens[k..k + attr.len()];
        if at.iter().zip(&attr).any(|(t, a)| t.tok != *a) {
            continue;
        }
        let m = k + attr.len();
        let is_module = matches!(
            (tokens[m].tok, tokens[m + 1].tok, tokens[m + 2].tok),
            (Tok::Word("mod"), Tok::Word(_), Tok::Punct('{'))
        );
        if is_module && matching(tokens, m + 2) == Some(tokens.len() - 1) {
            return t.line - 1;
        }
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A function of `n` body lines named `name`.
    fn function(name: &str, n: usize) -> String {
        let mut s = format!("fn {name}() {{\n");
        for _ in 0..n - 2 {
            s.push_str("    let x = 1;\n");
        }
        s.push_str("}\n");
        s
    }

    #[test]
    fn counts_bodies_from_brace_to_brace() {
        let src = format!(
            "{}{}",
            function("short", MAX_FN_LINES),
            function("long", MAX_FN_LINES + 1)
        );
        let found = offenders_in("a.rs", &src);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].function.as_deref(), Some("long"));
        assert_eq!(found[0].line, MAX_FN_LINES + 1);
        assert_eq!(found[0].lines, MAX_FN_LINES + 1);
        assert_eq!(
            found[0].to_string(),
            format!(
                "a.rs:{}: fn long has a {}-line body (limit {MAX_FN_LINES})",
                MAX_FN_LINES + 1,
                MAX_FN_LINES + 1
            )
        );
    }

    #[test]
    fn braces_in_strings_comments_and_chars_do_not_count() {
        let src = r####"
fn tricky<'a>(x: &'a str, y: [u8; 4]) -> [u32; 2] where 'a: 'a {
    let a = "}}} \" }";
    let b = r#"}" }"#;
    let c = br##"}"# }"##;
    let d = b"}";
    let e = '}';
    let f = '\u{7d}';
    let g = b'}';
    let i = ['\\', '\'', '{'];
    // }
    /* } /* nested } */ } */
    let h = |v: &'a str| v.len();
    [0, 1]
}
fn after() -> u8 {
    1
}
trait T {
    fn declared(&self) -> [u8; 2];
    fn with_default(&self) {}
}
"####;
        let tokens = tokens(src);
        let found = functions(&tokens);
        let names: Vec<_> = found.iter().map(|f| (f.0, f.1, f.2)).collect();
        assert_eq!(
            names,
            [("tricky", 2, 14), ("after", 16, 3), ("with_default", 21, 1)]
        );
    }

    #[test]
    fn a_trailing_test_module_does_not_count_towards_the_file() {
        let body = "const A: u8 = 1;\n".repeat(MAX_FILE_LINES);
        let tests = "#[cfg(test)]\nmod tests {\n    #[test]\n    fn t() {}\n}\n";
        assert!(offenders_in("ok.rs", &format!("{body}{tests}")).is_empty());
        // Code after the test module: the whole file counts.
        let after = format!("{body}{tests}const B: u8 = 2;\n");
        let found = offenders_in("long.rs", &after);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].lines, MAX_FILE_LINES + 6);
        assert_eq!(
            found[0].to_string(),
            format!(
                "long.rs:1: {} lines before its tests (limit {MAX_FILE_LINES})",
                MAX_FILE_LINES + 6
            )
        );
        let over = format!("{body}const B: u8 = 2;\n{tests}");
        assert_eq!(offenders_in("over.rs", &over)[0].lines, MAX_FILE_LINES + 1);
    }

    #[test]
    fn areas_name_the_crate_or_folder() {
        assert_eq!(area("crates/cli/src/cmd_bench.rs"), "crates/cli");
        assert_eq!(area("xtask/src/size.rs"), "xtask");
        assert_eq!(area("tests/conformance.rs"), "tests");
    }
}
