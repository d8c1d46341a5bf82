//! Writes the generated part of the Python type stubs `stark-python/python/starkrs/__init__.pyi`:
//! the model parameter classes, rendered from the library's field tables (`stark::params`),
//! between the `BEGIN` and `END` marker lines; the rest of the file is written by hand.
//!
//! `cargo run -p stark-codegen --bin gen_stubs` rewrites the section; its test (run by
//! `cargo test --workspace`) fails when the committed stubs differ from the tables. It lives
//! here, not in stark-python, so that the test needs no build of the extension (PyO3).

use stark::params::{doc_text, FieldKind, ParamFields};
use std::fmt::Write;
use std::process::ExitCode;

#[path = "../../../stark-python/src/param_list.rs"]
mod param_list;

/// The stub file, from the crate directory.
const PYI: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../stark-python/python/starkrs/__init__.pyi"
);
/// The line opening the generated section.
const BEGIN: &str =
    "# <generated> Parameter classes, from the library's field tables: `cargo run -p stark-codegen --bin gen_stubs`.";
/// The line closing it.
const END: &str = "# </generated>";

/// One class: its Python name, doc lines and fields.
struct Class {
    name: &'static str,
    doc: &'static [&'static str],
    fields: &'static [stark::params::FieldDoc],
}

/// Every parameter class, in the order of `param_list.rs`.
fn classes() -> Vec<Class> {
    macro_rules! list {
        ($($name:ident => $rust:path),* $(,)?) => {
            vec![$(Class {
                name: stringify!($name),
                doc: <$rust as ParamFields>::DOC,
                fields: <$rust as ParamFields>::FIELDS,
            }),*]
        };
    }
    param_list::param_classes!(list)
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
        out.push_str(&docstring(&doc_text(c.doc)));
        let mut args = Vec::new();
        for f in c.fields {
            let ty = match f.kind {
                FieldKind::Float => "float",
                FieldKind::Bool => "bool",
            };
            writeln!(out, "    {}: {ty}", f.name).unwrap();
            out.push_str(&docstring(&f.doc_text()));
            args.push(format!("{}: {ty} = ...", f.name));
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
            assert!(!doc_text(c.doc).is_empty(), "{} has no doc", c.name);
            for f in c.fields {
                assert!(!f.doc_text().is_empty(), "{}.{} has no doc", c.name, f.name);
            }
        }
    }
}
