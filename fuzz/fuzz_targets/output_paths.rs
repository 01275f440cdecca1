//! The safe writer's path checks: from the fuzz bytes, a small tree of regular files,
//! folders, symbolic links to decoys outside and FIFOs is built in a fresh folder, and
//! outputs are written into it through `write_atomic` and `OutputSet`. Checked after
//! each write: success exactly when every target is a regular file or absent (and its
//! folders real folders), the written content in place on success, the tree otherwise
//! unchanged (every non-regular entry kept, nothing changed on failure), the decoys
//! untouched, and no temporary file or staging folder left behind.
#![no_main]
use era_io::atomic::{write_atomic, OutputSet};
use libfuzzer_sys::fuzz_target;
use std::collections::BTreeMap;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;

/// Names in the output folder; none is a folder prefix of another except through
/// `pairs` and `sub`, which are only ever planted or created as folders by the sets.
const NAMES: [&str; 8] = [
    "a.csv",
    "b.json",
    "c",
    "pairs",
    "pairs/p.png",
    "sub",
    "sub/deep/d.uff",
    ".era-tmp-1-x.csv",
];

#[derive(Debug, Clone, PartialEq)]
enum Entry {
    File(Vec<u8>),
    Dir,
    Link(std::path::PathBuf),
    Fifo,
    Other,
}

fn snapshot(root: &Path) -> BTreeMap<String, Entry> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Entry>) {
        let Ok(rd) = std::fs::read_dir(dir) else {
            return;
        };
        for e in rd.flatten() {
            let p = e.path();
            let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
            let t = e.file_type().unwrap();
            let v = if t.is_symlink() {
                Entry::Link(std::fs::read_link(&p).unwrap())
            } else if t.is_dir() {
                walk(root, &p, out);
                Entry::Dir
            } else if t.is_file() {
                Entry::File(std::fs::read(&p).unwrap())
            } else if t.is_fifo() {
                Entry::Fifo
            } else {
                Entry::Other
            };
            out.insert(rel, v);
        }
    }
    let mut out = BTreeMap::new();
    walk(root, root, &mut out);
    out
}

/// Whether `name` may be written in a tree like `tree`: its folders real folders or
/// absent, itself a regular file or absent.
fn writable(tree: &BTreeMap<String, Entry>, name: &str) -> bool {
    let parts: Vec<&str> = name.split('/').collect();
    for k in 1..parts.len() {
        match tree.get(&parts[..k].join("/")) {
            None | Some(Entry::Dir) => {}
            _ => return false,
        }
    }
    matches!(tree.get(name), None | Some(Entry::File(_)))
}

fn plant(out: &Path, decoys: &Path, name: &str, kind: u8) {
    let p = out.join(name);
    // Every folder on the way, inside `out`, must be a real folder (created when
    // missing): planting through a link would reach the decoys, and the harness itself
    // must not touch them.
    let parts: Vec<&str> = name.split('/').collect();
    let mut dir = out.to_path_buf();
    for part in &parts[..parts.len() - 1] {
        dir.push(part);
        match std::fs::symlink_metadata(&dir) {
            Ok(m) if m.file_type().is_dir() => {}
            Ok(_) => return,
            Err(_) => {
                if std::fs::create_dir(&dir).is_err() {
                    return;
                }
            }
        }
    }
    let _ = match kind % 5 {
        // create_new: an entry planted earlier under the same name (a FIFO would block
        // a plain open) is left as it is.
        0 => std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&p)
            .and_then(|mut f| std::io::Write::write_all(&mut f, b"old")),
        1 => std::fs::create_dir(&p),
        2 => std::os::unix::fs::symlink(decoys.join("decoy.txt"), &p),
        3 => std::os::unix::fs::symlink(decoys.join("dir"), &p),
        _ => {
            let c = std::ffi::CString::new(p.as_os_str().as_encoded_bytes()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            unsafe { libc::mkfifo(c.as_ptr(), 0o644) };
            Ok(())
        }
    };
}

fn no_leftovers(tree: &BTreeMap<String, Entry>) {
    for name in tree.keys() {
        let last = name.rsplit('/').next().unwrap();
        assert!(
            !(last.starts_with(".era-staging-")
                || (last.starts_with(".era-tmp-") && last != ".era-tmp-1-x.csv")),
            "left behind: {name}"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 || data.len() > 64 {
        return;
    }
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("out");
    let decoys = root.path().join("decoys");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(decoys.join("dir")).unwrap();
    std::fs::write(decoys.join("decoy.txt"), b"decoy").unwrap();
    let decoys_before = snapshot(&decoys);

    let planted = (data[0] % 6) as usize;
    for k in 0..planted.min(data.len() - 1) {
        let b = data[1 + k];
        plant(&out, &decoys, NAMES[(b as usize) % NAMES.len()], b / 8);
    }
    for (step, chunk) in data[1 + planted.min(data.len() - 1)..]
        .chunks(2)
        .enumerate()
    {
        let before = snapshot(&out);
        let payload = format!("step {step}").into_bytes();
        let op = chunk[0];
        let mask = chunk.get(1).copied().unwrap_or(1);
        let (targets, ok) = if op % 2 == 0 {
            // One top-level file (a folder on the way could be a link: write_atomic
            // follows the user's folder, so only direct children are fuzzed here).
            let name = NAMES[(op as usize / 2) % 3 + if op & 0x40 != 0 { 5 } else { 0 }]
                .split('/')
                .next()
                .unwrap();
            let r = write_atomic(&out.join(name), &payload);
            (vec![name.to_string()], (r.is_ok(), writable(&before, name)))
        } else {
            // A set of names, none a folder of another.
            let mut chosen: Vec<&str> = Vec::new();
            for (i, n) in NAMES.iter().enumerate() {
                if mask & (1 << i) != 0
                    && !chosen
                        .iter()
                        .any(|c| n.starts_with(&format!("{c}/")) || c.starts_with(&format!("{n}/")))
                {
                    chosen.push(n);
                }
            }
            if chosen.is_empty() {
                continue;
            }
            let expected = chosen.iter().all(|n| writable(&before, n));
            let result = (|| -> Result<(), era_io::IoError> {
                let mut set = OutputSet::new(&out)?;
                for n in &chosen {
                    let staged = set.stage(n)?;
                    write_atomic(&staged, &payload)?;
                }
                set.commit()?;
                Ok(())
            })();
            (
                chosen.iter().map(|s| s.to_string()).collect(),
                (result.is_ok(), expected),
            )
        };
        let after = snapshot(&out);
        assert_eq!(
            ok.0, ok.1,
            "{targets:?}: success {} expected {}",
            ok.0, ok.1
        );
        if ok.0 {
            for t in &targets {
                assert_eq!(after.get(t), Some(&Entry::File(payload.clone())), "{t}");
            }
            for (name, entry) in &before {
                if !targets.contains(name) {
                    assert_eq!(after.get(name), Some(entry), "{name} changed");
                }
            }
            for name in after.keys() {
                assert!(
                    before.contains_key(name)
                        || targets
                            .iter()
                            .any(|t| t == name || t.starts_with(&format!("{name}/"))),
                    "{name} appeared"
                );
            }
        } else {
            assert_eq!(after, before, "a failed write changed the tree");
        }
        no_leftovers(&after);
        assert_eq!(snapshot(&decoys), decoys_before, "a decoy was touched");
    }
});
