//! The crate's modules form no cycle (docs/architecture.md): a module that uses another
//! (`crate::a::b` or `super::b` paths outside its unit tests) may not be used by it,
//! directly or through others. A parent declaring a child (`mod x;`) is not a use, nor is
//! a use between a module and its own descendants.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Module path (`crate::render::plan`) of every .rs file under `src`.
fn modules(src: &Path) -> BTreeMap<String, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(src).unwrap().with_extension("");
                let mut parts: Vec<String> = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
                if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
                    parts.pop();
                }
                let name = std::iter::once("crate".to_string()).chain(parts).collect::<Vec<_>>().join("::");
                out.insert(name, p);
            }
        }
    }
    out
}

/// The modules `name` (file `path`) uses.
fn uses(name: &str, path: &Path, all: &BTreeMap<String, PathBuf>) -> BTreeSet<String> {
    let mut src = std::fs::read_to_string(path).unwrap();
    if let Some(i) = src.find("#[cfg(test)]") {
        src.truncate(i);
    }
    // What `super` names: the parent of this module.
    let parent = name.rsplit_once("::").map_or("crate", |(p, _)| p).to_string();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = BTreeSet::new();
    for start in ["crate::", "super::"] {
        for (i, _) in src.match_indices(start) {
            if src[..i].chars().next_back().is_some_and(ident) {
                continue;
            }
            let head: String = src[i..].chars().take_while(|&c| ident(c) || c == ':').collect();
            // `super::{a::b, c}`: each entry of a brace group is a path too.
            let rest = &src[i + head.len()..];
            let mut paths = vec![head.clone()];
            if let Some(group) = rest.strip_prefix('{').and_then(|r| r.split_once('}')).map(|(g, _)| g) {
                paths = group.split(',').map(|e| format!("{head}{}", e.trim())).collect();
            }
            for path in paths {
                let mut parts = path.split("::").filter(|p| !p.is_empty());
                let mut cur = if parts.next() == Some("crate") { "crate".to_string() } else { parent.clone() };
                let mut best = None;
                for p in parts {
                    let p: String = p.chars().take_while(|&c| ident(c)).collect();
                    if p == "super" {
                        cur = cur.rsplit_once("::").map_or("crate".to_string(), |(a, _)| a.to_string());
                        continue;
                    }
                    cur = format!("{cur}::{p}");
                    if all.contains_key(&cur) {
                        best = Some(cur.clone());
                    }
                }
                if let Some(b) = best {
                    let related =
                        b == name || b.starts_with(&format!("{name}::")) || name.starts_with(&format!("{b}::"));
                    if !related {
                        out.insert(b);
                    }
                }
            }
        }
    }
    out
}

#[test]
fn modules_form_no_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let all = modules(&src);
    let edges: BTreeMap<String, BTreeSet<String>> = all.iter().map(|(n, p)| (n.clone(), uses(n, p, &all))).collect();
    // Sanity: the graph is not empty (the renderer uses the GPU layer).
    assert!(edges["crate::render"].contains("crate::gpu"), "{:?}", edges["crate::render"]);
    let mut cycles = Vec::new();
    let mut state: BTreeMap<&str, u8> = BTreeMap::new();
    fn visit<'a>(
        u: &'a str,
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<&'a str, u8>,
        stack: &mut Vec<&'a str>,
        cycles: &mut Vec<String>,
    ) {
        state.insert(u, 1);
        stack.push(u);
        for v in &edges[u] {
            match state.get(v.as_str()) {
                Some(1) => {
                    let i = stack.iter().position(|s| s == v).unwrap();
                    cycles.push(format!("{} -> {v}", stack[i..].join(" -> ")));
                }
                Some(_) => {}
                None => visit(v, edges, state, stack, cycles),
            }
        }
        stack.pop();
        state.insert(u, 2);
    }
    for u in edges.keys() {
        if !state.contains_key(u.as_str()) {
            visit(u, &edges, &mut state, &mut Vec::new(), &mut cycles);
        }
    }
    assert!(cycles.is_empty(), "module cycles:\n{}", cycles.join("\n"));
}
