//! Writes the generated part of the Python type stubs `stark-python/python/starkrs/__init__.pyi`:
//! the settings, model parameter and material classes, rendered from the library's tables
//! (`stark::params`: `ParamFields` of the parameter structs, `Documented` of the settings and
//! materials), between the `BEGIN` and `END` marker lines; the rest of the file is written by
//! hand.
//!
//! `cargo run -p stark-codegen --bin gen_stubs` rewrites the section; its test (run by
//! `cargo test --workspace`) fails when the committed stubs differ from the tables. It lives
//! here, not in stark-python, so that the test needs no build of the extension (PyO3).

use stark::params::{doc_text, Documented, FieldKind, ParamFields};
use std::fmt::Write;
use std::process::ExitCode;
use strum::VariantNames;

#[path = "../../../stark-python/src/param_list.rs"]
mod param_list;

/// The stub file, from the crate directory.
const PYI: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../stark-python/python/starkrs/__init__.pyi"
);
/// The line opening the generated section.
const BEGIN: &str =
    "# <generated> Settings, parameter and material classes, from the library's tables: `cargo run -p stark-codegen --bin gen_stubs`.";
/// The line closing it.
const END: &str = "# </generated>";

/// One field: its name, its type as an attribute and as a constructor argument, its doc.
struct Field {
    name: &'static str,
    attribute: String,
    argument: String,
    doc: String,
}

/// One class: its Python name, doc, fields and the stubs of its Python-only methods.
struct Class {
    name: &'static str,
    doc: String,
    fields: Vec<Field>,
    methods: &'static str,
}

/// The Python type of a settings or material field, from its Rust type: as an attribute and as a
/// constructor argument.
fn python_type(rust_type: &str) -> (String, String) {
    let literal = |names: &[&str]| {
        let quoted: Vec<_> = names.iter().map(|n| format!("\"{n}\"")).collect();
        format!("Literal[{}]", quoted.join(", "))
    };
    let same = |t: &str| (t.to_string(), t.to_string());
    match rust_type {
        "f64" => same("float"),
        "bool" => same("bool"),
        "usize" => same("int"),
        "String" => same("str"),
        "PathBuf" => same("Union[str, os.PathLike[str]]"),
        "Option<f64>" => same("Optional[float]"),
        "[f64;3]" => ("NDArray[np.float64]".into(), "ArrayLike".into()),
        "Bending" => same("Union[FlatBendingParams, DihedralBendingParams, None]"),
        "LinearSolver" => same(&literal(stark::settings::LinearSolver::VARIANTS)),
        "Projection" => same(&literal(stark::settings::Projection::VARIANTS)),
        "FrameFormat" => same(&literal(stark::settings::FrameFormat::VARIANTS)),
        "BarrierKind" => same(&literal(stark::contact::BarrierKind::VARIANTS)),
        "PairHessian" => same(&literal(stark::contact::PairHessian::VARIANTS)),
        // Nested settings and parameter structs: the Python class of the same name.
        t if class_names().contains(&t) => same(t),
        t => panic!("no Python type for the Rust type `{t}`: add it to gen_stubs' python_type"),
    }
}

/// The Python names of the settings, parameter and material classes (`param_list.rs`).
fn class_names() -> Vec<&'static str> {
    macro_rules! names {
        ($($name:ident => $rust:path),* $(,)?) => {
            vec![$(stringify!($name)),*]
        };
    }
    let mut all = param_list::settings_classes!(names);
    all.extend(param_list::param_classes!(names));
    all.extend(param_list::material_classes!(names));
    all
}

/// The stubs of the methods a class has in Python only (written in stark-python/src/params.rs;
/// the stub test compares their docstrings with the extension's).
fn python_methods(class: &str) -> &'static str {
    match class {
        "Settings" => "    def validate(self) -> None:\n        \"\"\"Check the values; raises `StarkError` naming the field.\"\"\"\n",
        "LineMaterial" => "    @staticmethod\n    def elastic_rubber_band() -> LineMaterial:\n        \"\"\"Elastic rubber band: 0.05 kg/m, r = 2 mm, E = 1e4 Pa, strain limit 10%.\"\"\"\n",
        "VolumeMaterial" => "    @staticmethod\n    def soft_rubber() -> VolumeMaterial:\n        \"\"\"Soft rubber: 1000 kg/m³, E = 1e4 Pa, ν = 0.3, strain limit 100%, inertial damping 0.1/s.\"\"\"\n",
        "SurfaceMaterial" => "    @staticmethod\n    def cotton_fabric() -> SurfaceMaterial:\n        \"\"\"Cotton fabric: 0.2 kg/m², 1 mm thick, E = 5e3 Pa, ν = 0.3, strain limit 10%, flat bending 1e-6 N·m.\"\"\"\n",
        _ => "",
    }
}

/// Every class, in the order of `param_list.rs`: settings, parameters, materials.
fn classes() -> Vec<Class> {
    macro_rules! documented {
        ($($name:ident => $rust:path),* $(,)?) => {
            vec![$({
                let fields = <$rust as Documented>::FIELDS
                    .iter()
                    .map(|f| {
                        let (attribute, argument) = python_type(&f.rust_type());
                        Field { name: f.name, attribute, argument, doc: f.doc_text() }
                    })
                    .collect();
                Class {
                    name: stringify!($name),
                    doc: doc_text(<$rust as Documented>::DOC),
                    fields,
                    methods: python_methods(stringify!($name)),
                }
            }),*]
        };
    }
    macro_rules! params {
        ($($name:ident => $rust:path),* $(,)?) => {
            vec![$({
                let fields = <$rust as ParamFields>::FIELDS
                    .iter()
                    .map(|f| {
                        let ty = match f.kind {
                            FieldKind::Float => "float",
                            FieldKind::Bool => "bool",
                        };
                        Field { name: f.name, attribute: ty.into(), argument: ty.into(), doc: f.doc_text() }
                    })
                    .collect();
                Class {
                    name: stringify!($name),
                    doc: doc_text(<$rust as ParamFields>::DOC),
                    fields,
                    methods: "",
                }
            }),*]
        };
    }
    let mut all = param_list::settings_classes!(documented);
    all.extend(param_list::param_classes!(params));
    all.extend(param_list::material_classes!(documented));
    all
}

/// A docstring indented by four spaces (continuation lines too).
fn docstring(text: &str) -> String {
    assert!(
        !text.contains("\"\"\"") && !text.contains('\\'),
        "docstring needs escaping: {text}"
    );
    format!("    \"\"\"{}\"\"\"\n", text.replace('\n', "\n    "))
}

/// The generated section, without the markers.
fn render() -> String {
    let mut out = String::new();
    for c in classes() {
        let name = c.name;
        out.push_str("\n@final\n");
        writeln!(out, "class {name}:").unwrap();
        out.push_str(&docstring(&c.doc));
        let mut args = Vec::new();
        for f in &c.fields {
            writeln!(out, "    {}: {}", f.name, f.attribute).unwrap();
            out.push_str(&docstring(&f.doc));
            args.push(format!("{}: {} = ...", f.name, f.argument));
        }
        writeln!(out, "    def __new__(cls, *, {}) -> {name}:", args.join(", ")).unwrap();
        out.push_str("    ");
        out.push_str(&docstring("Defaults of the library, with the given fields replaced."));
        out.push_str("    def to_dict(self) -> dict[str, Any]:\n");
        out.push_str("    ");
        out.push_str(&docstring(
            "The fields as a plain dict (nested settings as nested dicts).",
        ));
        writeln!(out, "    def copy(self) -> {name}:").unwrap();
        out.push_str("    ");
        out.push_str(&docstring("A deep copy (nested settings are copied too)."));
        writeln!(out, "    def __copy__(self) -> {name}: ...").unwrap();
        writeln!(out, "    def __deepcopy__(self, memo: Any) -> {name}: ...").unwrap();
        out.push_str(c.methods);
    }
    out.push('\n');
    out
}

/// The stub file with its generated section replaced.
fn splice(pyi: &str) -> Result<String, String> {
    let start = pyi.find(BEGIN).ok_or(format!("no line '{BEGIN}' in {PYI}"))?;
    let body = start + BEGIN.len() + 1;
    let end = pyi[body..]
        .find(END)
        .ok_or(format!("no line '{END}' after the opening one in {PYI}"))?
        + body;
    Ok(format!("{}{}{}", &pyi[..body], render(), &pyi[end..]))
}

fn main() -> ExitCode {
    let result = std::fs::read_to_string(PYI)
        .map_err(|e| format!("{PYI}: {e}"))
        .and_then(|old| splice(&old).map(|new| (old, new)))
        .and_then(|(old, new)| {
            if old == new {
                println!("{PYI} is up to date");
                Ok(())
            } else {
                std::fs::write(PYI, new).map_err(|e| format!("{PYI}: {e}"))?;
                println!("wrote the parameter classes into {PYI}");
                Ok(())
            }
        });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gen_stubs: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn committed_stubs_match_the_tables() {
        let pyi = std::fs::read_to_string(PYI).unwrap();
        let expected = splice(&pyi).unwrap();
        assert!(
            pyi == expected,
            "the parameter classes in {PYI} differ from the library's field tables; regenerate them with `cargo run -p stark-codegen --bin gen_stubs`"
        );
    }

    #[test]
    fn every_field_and_class_is_documented() {
        for c in classes() {
            assert!(!c.doc.is_empty(), "{} has no doc", c.name);
            for f in &c.fields {
                assert!(!f.doc.is_empty(), "{}.{} has no doc", c.name, f.name);
            }
        }
    }
}
