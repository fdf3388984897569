//! The contact solver's stages own their state (issue #49): no module of
//! `sim-core/src/contact/` mutates a field it does not own.
//!
//! The stages and the state each owns:
//! - `world` (`World`: the chain, the walls and their pieces, the loads, the settings);
//! - `committed` (`Committed`, `StepStart`: the equilibrium the last step reached);
//! - `broad_phase` (`BroadPhase`: the postures it measures pairs in);
//! - `step_solver` (`StepSolver` and the semismooth Newton method's `Ssn`, `Equations`,
//!   `NewtonSystem`: scratch space, repair memory, counters);
//! - `certifier` (`Certifier`: a view of the world and the committed state, no state);
//! - `driver` (`QuasiStatic`, `Secant`, `SavedState`: what steering the steps needs).
//!
//! Rust lets only the module that declares a private field (and that module's children)
//! name it, to read or to write it. So a stage's state is written only by its own code when
//! (1) every field of its state structs is visible within the stage's module and no
//! farther, and (2) every `impl` of those structs is written inside the stage's module.
//! The test checks both on the sources, parsed with `syn`, and (3), for each assignment or
//! `&mut` borrow of a `self.field` in an `impl` block, that the block's type is a state
//! struct of the file's own stage or a type outside every stage (a value passed between
//! them). A stage struct renamed or moved fails the test until this list says where it is.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use syn::visit::Visit;

/// The stages: the module under `contact` (a file or a folder) and its state structs.
const STAGES: &[(&str, &[&str])] = &[
    ("world", &["World"]),
    ("committed", &["Committed", "StepStart"]),
    ("broad_phase", &["BroadPhase"]),
    (
        "step_solver",
        &["StepSolver", "Ssn", "Equations", "NewtonSystem"],
    ),
    ("certifier", &["Certifier"]),
    ("driver", &["QuasiStatic", "Secant", "SavedState"]),
];

/// `sim-core/src/contact`.
fn contact_dir() -> PathBuf {
    Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../sim-core/src/contact"
    ))
    .to_path_buf()
}

/// Every `.rs` file under `dir`, with its module path below `contact` (`["driver",
/// "substep"]`; a `mod.rs` is its folder's module).
fn sources(dir: &Path, module: &[String], out: &mut Vec<(PathBuf, Vec<String>)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let mut here = module.to_vec();
        if path.is_dir() {
            here.push(name);
            sources(&path, &here, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            if name != "mod" {
                here.push(name);
            }
            out.push((path, here));
        }
    }
}

/// The module path (below `contact`; `None` for the whole crate) a field of visibility
/// `vis` declared in `module` is visible in.
fn visible_in(vis: &syn::Visibility, module: &[String]) -> Option<Vec<String>> {
    match vis {
        syn::Visibility::Inherited => Some(module.to_vec()),
        syn::Visibility::Public(_) => None,
        syn::Visibility::Restricted(r) => {
            let path: Vec<String> = r
                .path
                .segments
                .iter()
                .map(|s| s.ident.to_string())
                .collect();
            match path.first().map(String::as_str) {
                Some("self") => Some(module.to_vec()),
                Some("super") => {
                    // The crate's `contact` module itself is `[]`; above it, the crate.
                    let ups = path.iter().filter(|s| *s == "super").count();
                    (module.len() >= ups).then(|| module[..module.len() - ups].to_vec())
                }
                Some("crate") if path.len() >= 2 && path[1] == "contact" => {
                    Some(path[2..].to_vec())
                }
                _ => None,
            }
        }
    }
}

/// The stage a module belongs to (its first path segment, if that is a stage).
fn stage_of(module: &[String]) -> Option<&'static str> {
    let first = module.first()?;
    STAGES
        .iter()
        .find(|(stage, _)| first == stage)
        .map(|(stage, _)| *stage)
}

/// The stage whose state struct `name` is.
fn owner_of(name: &str) -> Option<&'static str> {
    STAGES
        .iter()
        .find(|(_, structs)| structs.contains(&name))
        .map(|(stage, _)| *stage)
}

/// The writes to `self.field...` in one `impl` block: assignments, compound assignments
/// and `&mut` borrows, by the field named first after `self`.
#[derive(Default)]
struct SelfWrites {
    fields: Vec<String>,
}

impl SelfWrites {
    fn note(&mut self, place: &syn::Expr) {
        // Down to the field right after `self` (`self.a.b[0] = ..` writes `a`).
        let mut expr = place;
        let mut first_field = None;
        loop {
            match expr {
                syn::Expr::Field(f) => {
                    if let syn::Member::Named(ident) = &f.member {
                        first_field = Some(ident.to_string());
                    }
                    expr = &f.base;
                }
                syn::Expr::Index(i) => expr = &i.expr,
                syn::Expr::Paren(p) => expr = &p.expr,
                syn::Expr::Path(p) if p.path.is_ident("self") => {
                    if let Some(field) = first_field {
                        self.fields.push(field);
                    }
                    return;
                }
                _ => return,
            }
        }
    }
}

impl<'ast> Visit<'ast> for SelfWrites {
    fn visit_expr_assign(&mut self, e: &'ast syn::ExprAssign) {
        self.note(&e.left);
        syn::visit::visit_expr_assign(self, e);
    }

    fn visit_expr_binary(&mut self, e: &'ast syn::ExprBinary) {
        use syn::BinOp::*;
        if matches!(
            e.op,
            AddAssign(_)
                | SubAssign(_)
                | MulAssign(_)
                | DivAssign(_)
                | RemAssign(_)
                | BitXorAssign(_)
                | BitAndAssign(_)
                | BitOrAssign(_)
                | ShlAssign(_)
                | ShrAssign(_)
        ) {
            self.note(&e.left);
        }
        syn::visit::visit_expr_binary(self, e);
    }

    fn visit_expr_reference(&mut self, e: &'ast syn::ExprReference) {
        if e.mutability.is_some() {
            self.note(&e.expr);
        }
        syn::visit::visit_expr_reference(self, e);
    }
}

/// The name of the type an `impl` block is for.
fn impl_type_name(item: &syn::ItemImpl) -> Option<String> {
    match &*item.self_ty {
        syn::Type::Path(p) => p.path.segments.last().map(|s| s.ident.to_string()),
        _ => None,
    }
}

/// A struct's fields, each with the module it is visible in (`None`: the crate).
type Fields = Vec<(String, Option<Vec<String>>)>;

/// Every struct and `impl` block of the contact solver, with their modules.
struct Parsed {
    /// Struct name -> (module, fields).
    structs: BTreeMap<String, (Vec<String>, Fields)>,
    /// (module, type name, fields of `self` the block writes).
    impls: Vec<(Vec<String>, String, Vec<String>)>,
}

fn parse() -> Parsed {
    let mut files = Vec::new();
    sources(&contact_dir(), &[], &mut files);
    assert!(files.len() > 10, "contact/ not found: {files:?}");
    let mut parsed = Parsed {
        structs: BTreeMap::new(),
        impls: Vec::new(),
    };
    for (path, module) in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let file = syn::parse_file(&text)
            .unwrap_or_else(|e| panic!("{}: does not parse: {e}", path.display()));
        collect(&file.items, &module, &mut parsed);
    }
    parsed
}

/// The structs and impls of `items` in `module` (inline modules, `#[cfg(test)] mod
/// tests { .. }`, are children of it).
fn collect(items: &[syn::Item], module: &[String], parsed: &mut Parsed) {
    for item in items {
        match item {
            syn::Item::Struct(s) => {
                let fields = s
                    .fields
                    .iter()
                    .map(|f| {
                        let name = f
                            .ident
                            .as_ref()
                            .map_or_else(|| "(tuple field)".to_string(), ToString::to_string);
                        (name, visible_in(&f.vis, module))
                    })
                    .collect();
                parsed
                    .structs
                    .insert(s.ident.to_string(), (module.to_vec(), fields));
            }
            syn::Item::Impl(i) => {
                if let Some(name) = impl_type_name(i) {
                    let mut writes = SelfWrites::default();
                    writes.visit_item_impl(i);
                    parsed.impls.push((module.to_vec(), name, writes.fields));
                }
            }
            syn::Item::Mod(m) => {
                if let Some((_, inner)) = &m.content {
                    let mut child = module.to_vec();
                    child.push(m.ident.to_string());
                    collect(inner, &child, parsed);
                }
            }
            _ => {}
        }
    }
}

/// (1) Every field of a stage's state is visible within the stage and no farther.
#[test]
fn every_stage_keeps_its_state_private_to_its_module() {
    let parsed = parse();
    let mut wrong = Vec::new();
    for (stage, structs) in STAGES {
        for name in *structs {
            let Some((module, fields)) = parsed.structs.get(*name) else {
                wrong.push(format!("{stage}: no struct {name} under contact/"));
                continue;
            };
            if stage_of(module) != Some(stage) {
                wrong.push(format!("{name} is declared in {module:?}, not in {stage}"));
            }
            assert!(
                !fields.is_empty() || *name == "Certifier",
                "{name} has no fields"
            );
            for (field, visible) in fields {
                let inside = visible
                    .as_ref()
                    .is_some_and(|v| v.first().map(String::as_str) == Some(*stage));
                if !inside {
                    let scope = visible.as_ref().map_or("the crate".to_string(), |v| {
                        format!("contact::{}", v.join("::"))
                    });
                    wrong.push(format!(
                        "{stage}: {name}::{field} is visible in {scope}, outside its stage"
                    ));
                }
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// (2) A stage's state structs are implemented only inside the stage, and (3) an `impl`
/// block writes fields of `self` only where `self` is its own stage's (or a value's).
#[test]
fn no_module_of_contact_mutates_a_field_it_does_not_own() {
    let parsed = parse();
    let mut wrong = Vec::new();
    let mut writes_seen = 0;
    for (module, ty, writes) in &parsed.impls {
        let here = stage_of(module);
        if let Some(owner) = owner_of(ty)
            && here != Some(owner)
        {
            wrong.push(format!(
                "contact::{}: impl {ty}, a state of {owner}, outside its stage",
                module.join("::")
            ));
        }
        if writes.is_empty() {
            continue;
        }
        writes_seen += writes.len();
        // `self` is `ty`: its fields written here must be `ty`'s, and `ty` this stage's
        // state (or a value type of no stage).
        match (owner_of(ty), here) {
            (Some(owner), Some(stage)) if owner != stage => wrong.push(format!(
                "contact::{}: writes {writes:?} of {ty}, owned by {owner}",
                module.join("::")
            )),
            (Some(owner), None) => wrong.push(format!(
                "contact::{}: writes {writes:?} of {ty}, owned by {owner}",
                module.join("::")
            )),
            _ => {}
        }
        if let Some((_, fields)) = parsed.structs.get(ty) {
            for field in writes {
                if !fields.iter().any(|(f, _)| f == field) {
                    wrong.push(format!(
                        "contact::{}: impl {ty} writes self.{field}, not a field of {ty}",
                        module.join("::")
                    ));
                }
            }
        }
    }
    // The scan sees the stages' writes (the committed state's commit, the broad phase's
    // postures, the solver's scratch space): a scan that finds none is broken.
    assert!(writes_seen > 50, "only {writes_seen} writes to self found");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The test itself: a field made `pub(crate)`, or an `impl` of a stage's state written in
/// another stage, is found.
#[test]
fn the_ownership_scan_finds_a_field_that_leaks_and_a_foreign_impl() {
    let file: syn::File = syn::parse_str(
        "pub(super) struct Committed { pub(crate) theta: Vec<f64>, beta: Vec<f64> }
         impl Committed { fn f(&mut self) { self.theta[0] = 1.0; self.beta.push(0.0); } }",
    )
    .unwrap();
    let mut parsed = Parsed {
        structs: BTreeMap::new(),
        impls: Vec::new(),
    };
    collect(&file.items, &["driver".to_string()], &mut parsed);
    let (module, fields) = &parsed.structs["Committed"];
    assert_eq!(module, &["driver".to_string()]);
    assert_eq!(fields[0], ("theta".to_string(), None));
    assert_eq!(
        fields[1],
        ("beta".to_string(), Some(vec!["driver".to_string()]))
    );
    let (impl_module, ty, writes) = &parsed.impls[0];
    assert_eq!(stage_of(impl_module), Some("driver"));
    assert_eq!(owner_of(ty), Some("committed"));
    // `self.beta.push(..)` is a method call: the scan counts assignments and `&mut`
    // borrows; the privacy rule (1) is what keeps a method from another stage out.
    assert_eq!(writes, &["theta".to_string()]);
    assert_eq!(
        visible_in(
            &syn::parse_str::<syn::Visibility>("pub(super)").unwrap(),
            &["step_solver".to_string(), "ssn".to_string()]
        ),
        Some(vec!["step_solver".to_string()])
    );
}
