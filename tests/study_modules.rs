//! The study layer has no import circle: its engine (the lab, trials, the
//! runner, references, agreement, plans, classes) knows no study, and no
//! two studies import each other, directly or around a loop. A circle
//! would mean a study cannot be added, changed or removed on its own
//! (issue "one engine, two fronts").
//!
//! The graph is read from the sources: an edge A → B for every
//! `crate::study::B` (or `crate::study::{B, ..}`) written in a file of the
//! top-level module A of `src/study/`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The engine: modules every study may use and that use no study.
const ENGINE: [&str; 12] = [
    "agreement",
    "catalog",
    "class",
    "cores",
    "lab",
    "parallel",
    "plans",
    "reference",
    "runner",
    "template",
    "trial",
    "mod",
];

type Graph = BTreeMap<String, BTreeSet<String>>;

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The modules a source names after `crate::study::`.
fn named(source: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, _) in source.match_indices("crate::study::") {
        let rest = &source[i + "crate::study::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let group = &group[..group.find('}').unwrap_or(group.len())];
            for item in group.split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.insert(name);
        }
    }
    out
}

fn graph() -> Graph {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/study");
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    let mut g = Graph::new();
    for f in files {
        let rel = f.strip_prefix(&root).unwrap();
        let first = rel.components().next().unwrap().as_os_str();
        let module = first.to_str().unwrap().trim_end_matches(".rs").to_string();
        let source = std::fs::read_to_string(&f).unwrap();
        let deps = g.entry(module.clone()).or_default();
        for d in named(&source) {
            if d != module {
                deps.insert(d);
            }
        }
    }
    g
}

/// A circle in `g`, if any, as the modules around it.
fn circle(g: &Graph) -> Option<Vec<String>> {
    fn visit(
        g: &Graph,
        node: &str,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(k) = path.iter().position(|p| p == node) {
            let mut c = path[k..].to_vec();
            c.push(node.to_string());
            return Some(c);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for d in g.get(node).into_iter().flatten() {
            if let Some(c) = visit(g, d, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    g.keys()
        .find_map(|n| visit(g, n, &mut Vec::new(), &mut done))
}

#[test]
fn the_study_layer_has_no_import_circle() {
    let g = graph();
    assert!(g.len() > 10, "read the study modules: {g:?}");
    if let Some(c) = circle(&g) {
        panic!("import circle in src/study/: {}", c.join(" → "));
    }
}

#[test]
fn the_engine_knows_no_study() {
    let g = graph();
    for m in ENGINE.iter().filter(|m| **m != "mod") {
        for d in g.get(*m).into_iter().flatten() {
            assert!(
                ENGINE.contains(&d.as_str()),
                "the engine module `{m}` imports the study `{d}`"
            );
        }
    }
}

/// The check itself finds a circle where there is one, and reads grouped
/// imports.
#[test]
fn a_circle_is_found() {
    let mut g = Graph::new();
    g.entry("lab".into()).or_default().insert("sweep".into());
    g.entry("sweep".into()).or_default().insert("trial".into());
    g.entry("trial".into()).or_default().insert("lab".into());
    let c = circle(&g).expect("a circle");
    assert_eq!(c.first(), c.last());
    assert_eq!(c.len(), 4);
    g.get_mut("trial").unwrap().clear();
    assert!(circle(&g).is_none());
    assert_eq!(
        named("use crate::study::{lab::Lab, trial};\nuse crate::study::runner::Keep;"),
        ["lab", "runner", "trial"].map(String::from).into()
    );
}
