//! No function in src/ is longer than [`MAX_LINES`] lines (from its `fn` line to its closing
//! brace): a longer one does several things and reads better as named steps.
//!
//! The scan is a small lexer, not a parser: it skips comments, string, raw string and char
//! literals, finds each `fn NAME` and counts braces from there to the body's end.

use std::path::{Path, PathBuf};

const MAX_LINES: usize = 120;

/// Every .rs file under `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A code token that matters here, with its 1-based line.
#[derive(Debug, PartialEq)]
enum Token {
    Open,
    Close,
    Semicolon,
    Ident(String),
}

/// The braces, semicolons and identifiers of `src` outside comments and literals.
fn tokens(src: &str) -> Vec<(usize, Token)> {
    let c: Vec<char> = src.chars().collect();
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    // Advances past `c[i]`, counting lines.
    let step = |i: &mut usize, line: &mut usize| {
        if c[*i] == '\n' {
            *line += 1;
        }
        *i += 1;
    };
    while i < c.len() {
        let next = c.get(i + 1).copied();
        match c[i] {
            '/' if next == Some('/') => {
                while i < c.len() && c[i] != '\n' {
                    i += 1;
                }
            }
            '/' if next == Some('*') => {
                let mut depth = 0;
                while i < c.len() {
                    if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                        depth += 1;
                        i += 1;
                    } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                        depth -= 1;
                        i += 1;
                    }
                    step(&mut i, &mut line);
                    if depth == 0 {
                        break;
                    }
                }
            }
            // A raw string: r"..." or r#"..."# (also br"...").
            'r' if (i == 0 || !ident(c[i - 1]) || c[i - 1] == 'b') && matches!(next, Some('"' | '#')) => {
                let mut j = i + 1;
                while c.get(j) == Some(&'#') {
                    j += 1;
                }
                if c.get(j) != Some(&'"') {
                    // An identifier such as `r#type`.
                    i += 1;
                    continue;
                }
                let hashes = j - i - 1;
                i = j + 1;
                while i < c.len() && !(c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#'))) {
                    step(&mut i, &mut line);
                }
                i += 1 + hashes;
            }
            '"' => {
                i += 1;
                while i < c.len() && c[i] != '"' {
                    if c[i] == '\\' {
                        step(&mut i, &mut line);
                    }
                    step(&mut i, &mut line);
                }
                i += 1;
            }
            // A char literal ('x', '\n', '\u{7b}'); otherwise a lifetime or a label.
            '\'' => {
                if next == Some('\\') {
                    i += 2;
                    while i < c.len() && c[i] != '\'' {
                        i += 1;
                    }
                    i += 1;
                } else if c.get(i + 2) == Some(&'\'') {
                    i += 3;
                } else {
                    i += 1;
                }
            }
            '{' => {
                out.push((line, Token::Open));
                i += 1;
            }
            '}' => {
                out.push((line, Token::Close));
                i += 1;
            }
            ';' => {
                out.push((line, Token::Semicolon));
                i += 1;
            }
            ch if ident(ch) => {
                let start = i;
                while i < c.len() && ident(c[i]) {
                    i += 1;
                }
                out.push((line, Token::Ident(c[start..i].iter().collect())));
            }
            _ => step(&mut i, &mut line),
        }
    }
    out
}

/// (name, first line, lines) of every function with a body in `src`.
fn functions(src: &str) -> Vec<(String, usize, usize)> {
    let toks = tokens(src);
    let mut out = Vec::new();
    for (k, (line, tok)) in toks.iter().enumerate() {
        let (Token::Ident(kw), Some((_, Token::Ident(name)))) = (tok, toks.get(k + 1)) else { continue };
        if kw != "fn" {
            continue;
        }
        // The body: the first brace before any semicolon (a declaration without one ends
        // at its semicolon; braces of a `where` clause's generics do not occur).
        let Some(open) = toks[k..].iter().position(|(_, t)| matches!(t, Token::Open | Token::Semicolon)) else {
            continue;
        };
        if toks[k + open].1 == Token::Semicolon {
            continue;
        }
        let mut depth = 0i32;
        for (end_line, t) in &toks[k + open..] {
            match t {
                Token::Open => depth += 1,
                Token::Close => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                out.push((name.clone(), *line, end_line - line + 1));
                break;
            }
        }
    }
    out
}

#[test]
fn the_scanner_measures_functions() {
    let src = "fn a() {\n    let s = \"}\";\n    let c = '{';\n    // }\n}\n\
               trait T {\n    fn b(&self);\n    fn c<'x>(&'x self) -> &'x str {\n        r#\"}\"#\n    }\n}\n\
               /* fn d() { */\nfn e() {}\n";
    let got = functions(src);
    let want = vec![("a".to_string(), 1, 5), ("c".to_string(), 8, 3), ("e".to_string(), 13, 1)];
    assert_eq!(got, want);
}

#[test]
fn no_function_in_src_is_over_the_limit() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut long = Vec::new();
    let mut count = 0;
    for path in rust_files(&src) {
        let text = std::fs::read_to_string(&path).unwrap();
        for (name, line, lines) in functions(&text) {
            count += 1;
            if lines > MAX_LINES {
                let rel = path.strip_prefix(env!("CARGO_MANIFEST_DIR")).unwrap().display().to_string();
                long.push(format!("{rel}:{line} {name}: {lines} lines"));
            }
        }
    }
    // Sanity: the scan found the crate's functions.
    assert!(count > 500, "only {count} functions found");
    assert!(long.is_empty(), "functions over {MAX_LINES} lines (split them into steps):\n{}", long.join("\n"));
}
