//! No file of a crate imports, directly or through others, a file that imports it back: the
//! reading order a newcomer follows is a tree, not a knot. Reads every crate's `src/*.rs`,
//! takes the `crate::<module>` paths outside comments and test modules, and searches the
//! graph for a cycle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Modules of one crate's `src/` and the sibling modules each one names as `crate::<m>`.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let files: Vec<_> = std::fs::read_dir(src)
        .expect("a crate's src/ is readable")
        .filter_map(|e| {
            let path = e.ok()?.path();
            (path.extension()? == "rs").then_some(path)
        })
        .collect();
    let names: BTreeSet<String> = files
        .iter()
        .filter_map(|p| Some(p.file_stem()?.to_str()?.to_owned()))
        .collect();
    let mut graph = BTreeMap::new();
    for path in &files {
        let name = path.file_stem().unwrap().to_str().unwrap().to_owned();
        let text = std::fs::read_to_string(path).expect("a source file is readable");
        let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
        let mut uses = BTreeSet::new();
        for line in code.lines() {
            let line = line.split("//").next().unwrap_or("");
            for (i, _) in line.match_indices("crate::") {
                let rest = &line[i + "crate::".len()..];
                let module: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if names.contains(&module) && module != name {
                    uses.insert(module);
                }
            }
        }
        graph.insert(name, uses);
    }
    graph
}

/// A cycle through `start`, if any (depth-first search).
fn cycle_from(graph: &BTreeMap<String, BTreeSet<String>>, start: &str) -> Option<Vec<String>> {
    let mut stack = vec![(start.to_owned(), vec![start.to_owned()])];
    let mut seen = BTreeSet::new();
    while let Some((node, path)) = stack.pop() {
        for next in &graph[&node] {
            if next == start {
                let mut cycle = path.clone();
                cycle.push(start.to_owned());
                return Some(cycle);
            }
            if seen.insert(next.clone()) {
                let mut longer = path.clone();
                longer.push(next.clone());
                stack.push((next.clone(), longer));
            }
        }
    }
    None
}

#[test]
fn no_crate_has_an_import_cycle_between_its_files() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut crates: Vec<_> = std::fs::read_dir(root.join("crates"))
        .expect("crates/ is readable")
        .filter_map(|e| Some(e.ok()?.path().join("src")))
        .filter(|p| p.is_dir())
        .collect();
    crates.push(root.join("tests/src"));
    assert!(crates.len() >= 6, "{crates:?}");
    let mut cycles = Vec::new();
    for src in &crates {
        let graph = module_graph(src);
        for module in graph.keys() {
            if let Some(cycle) = cycle_from(&graph, module) {
                cycles.push(format!("{}: {}", src.display(), cycle.join(" -> ")));
            }
        }
    }
    assert!(cycles.is_empty(), "import cycles:\n{}", cycles.join("\n"));
}

/// The checker finds a cycle where there is one.
#[test]
fn a_cycle_is_found() {
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec!["a"]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_owned(), v.into_iter().map(str::to_owned).collect()))
    .collect();
    assert_eq!(
        cycle_from(&graph, "a"),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    assert_eq!(cycle_from(&graph, "d"), None);
}

/// The render crate's groups (the first folder or file under `src/`) and the groups each
/// one's files name as `crate::<group>`, outside comments and test modules, every folder
/// read.
fn group_imports(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    let mut folders = vec![src.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("a source folder is readable") {
            let path = entry.expect("a folder entry is readable").path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    let mut imports: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for path in &files {
        let relative = path.strip_prefix(src).expect("a file under src/");
        let first = relative.components().next().expect("a file has a name");
        let group = Path::new(first.as_os_str())
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("a UTF-8 file name")
            .to_owned();
        let text = std::fs::read_to_string(path).expect("a source file is readable");
        let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
        let uses = imports.entry(group.clone()).or_default();
        for line in code.lines() {
            let line = line.split("//").next().unwrap_or("");
            for (i, _) in line.match_indices("crate::") {
                let named: String = line[i + "crate::".len()..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if named != group {
                    uses.insert(named);
                }
            }
        }
    }
    imports
}

/// The imports among `imports` that point against the layers' direction: the scenes below
/// the tracers, the tracers below the measurements, the command line above everything
/// (`(from, to)` pairs).
fn against_the_direction(imports: &BTreeMap<String, BTreeSet<String>>) -> Vec<(String, String)> {
    let forbidden: &[(&str, &[&str])] = &[
        ("scene", &["trace", "lab", "cli"]),
        ("trace", &["lab", "cli"]),
        ("lab", &["cli"]),
        ("lib", &["cli"]),
    ];
    let mut wrong = Vec::new();
    for &(from, targets) in forbidden {
        for to in imports.get(from).into_iter().flatten() {
            if targets.contains(&to.as_str()) {
                wrong.push((from.to_owned(), to.clone()));
            }
        }
    }
    wrong
}

#[test]
fn the_render_crates_layers_import_one_way() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../crates/render/src");
    let imports = group_imports(&src);
    for group in ["scene", "trace", "lab", "cli"] {
        assert!(imports.contains_key(group), "no {group} in {imports:?}");
    }
    // The reader sees the files of nested folders: trace/ names scene/ somewhere below it.
    assert!(imports["trace"].contains("scene"), "{imports:?}");
    let wrong = against_the_direction(&imports);
    assert!(wrong.is_empty(), "imports against the layers: {wrong:?}");
}

/// The direction check finds an import that points the wrong way.
#[test]
fn an_import_against_the_layers_is_found() {
    let imports: BTreeMap<String, BTreeSet<String>> = [
        ("scene", vec!["trace"]),
        ("trace", vec!["scene"]),
        ("lab", vec!["trace", "scene"]),
        ("cli", vec!["lab"]),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_owned(), v.into_iter().map(str::to_owned).collect()))
    .collect();
    assert_eq!(
        against_the_direction(&imports),
        vec![("scene".to_owned(), "trace".to_owned())]
    );
}
