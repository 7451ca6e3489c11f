//! The library's layers (docs/design.md, "Layers"): every `crate::…` path in `src/` names a
//! module of the same top-level module or of one below it in [`ORDER`], so that geometry never
//! reaches for the solver, the solver never for the lab tests, and so on. A new top-level module
//! must be given its place here.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The top-level modules of `src/`, lowest layer first; a module may import only modules that
/// come before it.
const ORDER: &[&str] = &[
    // core
    "io",
    "limits",
    "quadrature",
    "converge",
    // geometry
    "mesh",
    "subdiv",
    "shell",
    "shape",
    // constitutive laws
    "material",
    // the model contract
    "model",
    // discretisations
    "assembly",
    "tri",
    // the solver
    "solve",
    // the virtual lab
    "scene",
    // lab data
    "dataset",
    // fitting
    "fit",
    // applications
    "synth",
    "atlas",
    "recommend",
    "render",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a file of `src/` belongs to (`None` for the crate root and binaries).
fn top_module(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel.components().next()?.as_os_str().to_str()?.to_string();
    if first == "bin" || first == "lib.rs" {
        return None;
    }
    Some(first.trim_end_matches(".rs").to_string())
}

/// The top-level modules named by `crate::name` and `crate::{a, b}` in code (comments and doc
/// comments, which may point anywhere, are left out).
fn imported(text: &str) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(at) = rest.find("crate::") {
            let before = &rest[..at];
            rest = &rest[at + "crate::".len()..];
            if before.ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                continue; // e.g. `kshell_crate::`
            }
            if let Some(group) = rest.strip_prefix('{') {
                let inner = group.split('}').next().unwrap_or("");
                for item in inner.split(',') {
                    let name: String = item
                        .trim()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    names.insert(name);
                }
            } else {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                names.insert(name);
            }
        }
    }
    names
}

#[test]
fn every_import_points_down_the_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let rank = |m: &str| ORDER.iter().position(|o| *o == m);
    let mut wrong = Vec::new();
    for file in &files {
        let Some(me) = top_module(&src, file) else {
            continue;
        };
        let Some(my_rank) = rank(&me) else {
            wrong.push(format!(
                "{}: module `{me}` has no place in ORDER",
                file.display()
            ));
            continue;
        };
        let text = std::fs::read_to_string(file).unwrap();
        for other in imported(&text) {
            match rank(&other) {
                Some(r) if r > my_rank => wrong.push(format!(
                    "{}: `{me}` imports `{other}`, a higher layer",
                    file.strip_prefix(&src).unwrap().display()
                )),
                _ => {}
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the layer order:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_import_reader_sees_paths_and_groups() {
    let text = "use crate::scene::X;\nuse crate::{fit, io::read};\n// crate::render in a comment\nlet a = crate::solve::newton();";
    let got: Vec<String> = imported(text).into_iter().collect();
    assert_eq!(got, ["fit", "io", "scene", "solve"]);
}
