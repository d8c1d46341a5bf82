//! How a [`SceneError`] finds its place: a path into the document ([`At`]), the untyped
//! document for spans and entry labels ([`Tree`]), and the context ([`Ctx`]) that turns a path and
//! a message into an error naming the file, line, column, entry and field.

pub use crate::error::SceneError;
use crate::error::StarkError;
use std::fmt::Write as _;
use std::ops::Range;
use toml::de::{DeTable, DeValue};

/// What the scene's builders return.
pub(super) type Res<T> = std::result::Result<T, SceneError>;

/// One step of a path into the document.
#[derive(Clone, Debug, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

/// A path into the document.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct At(Vec<Seg>);

impl At {
    pub(super) fn entry(kind: &str, index: usize) -> At {
        At(vec![Seg::Key(kind.into()), Seg::Index(index)])
    }
    pub(super) fn key(&self, key: &str) -> At {
        let mut p = self.clone();
        p.0.push(Seg::Key(key.into()));
        p
    }
    pub(super) fn index(&self, index: usize) -> At {
        let mut p = self.clone();
        p.0.push(Seg::Index(index));
        p
    }
    pub(super) fn keys<S: AsRef<str>>(&self, keys: &[S]) -> At {
        let mut p = self.clone();
        p.0.extend(keys.iter().map(|k| Seg::Key(k.as_ref().into())));
        p
    }
}

/// Entry arrays whose items are described by name rather than by index.
const ENTRY_KINDS: [&str; 12] = [
    "robot",
    "surface",
    "volume",
    "line",
    "obstacle",
    "prescribed",
    "attachment",
    "gravity_ramp",
    "friction",
    "disable_collision",
    "rigid_body",
    "joint",
];

/// The untyped document, for spans (TOML only) and entry labels.
pub(super) enum Tree<'a> {
    Toml(&'a DeTable<'a>),
    Json(&'a serde_json::Value),
}

impl Tree<'_> {
    pub(super) fn item_str(&self, kind: &str, index: usize, key: &str) -> Option<String> {
        match self {
            Tree::Toml(doc) => doc
                .get(kind)?
                .get_ref()
                .as_array()?
                .get(index)?
                .get_ref()
                .as_table()?
                .get(key)?
                .get_ref()
                .as_str()
                .map(str::to_string),
            Tree::Json(v) => v.get(kind)?.get(index)?.get(key)?.as_str().map(str::to_string),
        }
    }

    /// Whether entry `index` of `kind` gives the field `key`.
    fn item_has(&self, kind: &str, index: usize, key: &str) -> bool {
        match self {
            Tree::Toml(doc) => (|| {
                doc.get(kind)?
                    .get_ref()
                    .as_array()?
                    .get(index)?
                    .get_ref()
                    .as_table()?
                    .get(key)
            })()
            .is_some(),
            Tree::Json(v) => v
                .get(kind)
                .and_then(|k| k.get(index))
                .and_then(|e| e.get(key))
                .is_some(),
        }
    }

    /// The strings of an array field of an entry (`None` unless every item is a string).
    fn item_strs(&self, kind: &str, index: usize, key: &str) -> Option<Vec<String>> {
        match self {
            Tree::Toml(doc) => doc
                .get(kind)?
                .get_ref()
                .as_array()?
                .get(index)?
                .get_ref()
                .as_table()?
                .get(key)?
                .get_ref()
                .as_array()?
                .iter()
                .map(|v| v.get_ref().as_str().map(str::to_string))
                .collect(),
            Tree::Json(v) => v
                .get(kind)?
                .get(index)?
                .get(key)?
                .as_array()?
                .iter()
                .map(|v| v.as_str().map(str::to_string))
                .collect(),
        }
    }
}

/// What every builder needs to report an error: the file's name, its text and its untyped document.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    pub(super) text: &'a str,
    pub(super) tree: Tree<'a>,
    /// Span of the whole TOML document (errors there, such as a missing top-level field, have no
    /// path).
    pub(super) root_span: Option<Range<usize>>,
}

/// 1-based line and column (in characters) of a byte offset.
pub(super) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// The deepest path whose key or value span contains `pos`.
fn locate_in_table(table: &DeTable, pos: usize, path: &mut Vec<Seg>) -> bool {
    for (key, value) in table.iter() {
        path.push(Seg::Key(key.get_ref().to_string()));
        if key.span().contains(&pos) || locate_in_value(value.get_ref(), pos, path) {
            return true;
        }
        if value.span().contains(&pos) {
            return true;
        }
        path.pop();
    }
    false
}

fn locate_in_value(value: &DeValue, pos: usize, path: &mut Vec<Seg>) -> bool {
    match value {
        DeValue::Table(t) => locate_in_table(t, pos, path),
        DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                path.push(Seg::Index(i));
                if locate_in_value(item.get_ref(), pos, path) || item.span().contains(&pos) {
                    return true;
                }
                path.pop();
            }
            false
        }
        _ => false,
    }
}

impl Ctx<'_> {
    /// Span of the deepest element of `at` that exists in the document (a key's span for keys).
    fn span_of(&self, at: &At) -> Option<Range<usize>> {
        let Tree::Toml(doc) = self.tree else {
            return None;
        };
        let mut span = None;
        let mut table: Option<&DeTable> = Some(doc);
        let mut array: Option<&[toml::Spanned<DeValue>]> = None;
        for seg in &at.0 {
            let value = match seg {
                Seg::Key(k) => {
                    let Some((key, value)) = table.and_then(|t| t.get_key_value(k.as_str())) else {
                        break;
                    };
                    span = Some(key.span());
                    value
                }
                Seg::Index(i) => {
                    let Some(item) = array.and_then(|a| a.get(*i)) else {
                        break;
                    };
                    span = Some(item.span());
                    item
                }
            };
            table = value.get_ref().as_table();
            array = value.get_ref().as_array().map(|a| &a[..]);
        }
        span
    }

    /// Span of the value at `at` (an entry's field).
    fn value_span(&self, at: &At) -> Option<Range<usize>> {
        let (Tree::Toml(doc), [Seg::Key(kind), Seg::Index(i), Seg::Key(key)]) = (&self.tree, &at.0[..]) else {
            return None;
        };
        let entry = doc
            .get(kind.as_str())?
            .get_ref()
            .as_array()?
            .get(*i)?
            .get_ref()
            .as_table()?;
        entry.get(key.as_str()).map(|v| v.span())
    }

    fn entry_label(&self, kind: &str, index: usize) -> String {
        let field = |k: &str| self.tree.item_str(kind, index, k);
        let n = index + 1;
        if kind == "joint" && field("name").is_none() {
            let a = field("a").unwrap_or_else(|| "world".into());
            return match (field("type"), field("b")) {
                (Some(t), Some(b)) => format!("joint #{n} ({t} '{a}' to '{b}')"),
                _ => format!("joint #{n}"),
            };
        }
        match (field("name"), field("object"), field("a"), field("b")) {
            (Some(name), ..) => format!("{kind} '{name}'"),
            (None, Some(object), ..) => format!("{kind} #{n} (object '{object}')"),
            (None, None, Some(a), Some(b)) => format!("{kind} #{n} ('{a}' to '{b}')"),
            _ => match self.tree.item_strs(kind, index, "objects").as_deref() {
                Some([a, b]) => format!("{kind} #{n} ('{a}' and '{b}')"),
                _ => format!("{kind} #{n}"),
            },
        }
    }

    fn describe(&self, at: &At) -> String {
        let mut out = String::new();
        let mut rest = &at.0[..];
        if let [Seg::Key(kind), Seg::Index(i), tail @ ..] = &at.0[..] {
            if ENTRY_KINDS.contains(&kind.as_str()) {
                out = self.entry_label(kind, *i);
                rest = tail;
                if !rest.is_empty() {
                    out.push(' ');
                }
            }
        }
        for (j, seg) in rest.iter().enumerate() {
            match seg {
                Seg::Key(k) => {
                    if j > 0 {
                        out.push('.');
                    }
                    out.push_str(k);
                }
                Seg::Index(i) => {
                    let _ = write!(out, "[{i}]");
                }
            }
        }
        out
    }

    /// Whether the entry at `at` (`[kind, index]`) gives the field `key`.
    pub(super) fn gives(&self, at: &At, key: &str) -> bool {
        match &at.0[..] {
            [Seg::Key(kind), Seg::Index(i), ..] => self.tree.item_has(kind, *i, key),
            _ => false,
        }
    }

    /// An error at `at`; for "unknown field `x`" the path names the table holding `x`.
    pub(super) fn err(&self, at: &At, message: impl Into<String>) -> SceneError {
        let message = message.into();
        let (line, column) = self.span_of(at).map(|s| line_col(self.text, s.start)).unzip();
        let mut shown = at.clone();
        if let (Some(Seg::Key(last)), Some(unknown)) = (
            shown.0.last(),
            message
                .strip_prefix("unknown field `")
                .and_then(|m| m.split('`').next()),
        ) {
            if last == unknown {
                shown.0.pop();
            }
        }
        SceneError {
            file: self.file.to_string(),
            line,
            column,
            path: self.describe(&shown),
            message,
        }
    }

    /// A deserialisation error of the TOML document, located through its span. An error in a
    /// `[[joint]]`, whose span is the whole entry, is traced to its field by `joint_culprit`
    /// (`(index, message)` to `(key, message)`).
    pub(super) fn toml_error(
        &self,
        e: &toml::de::Error,
        joint_culprit: impl Fn(&Ctx, usize, &str) -> Option<(String, String)>,
    ) -> SceneError {
        let mut path = Vec::new();
        let mut line_column = None;
        if let Some(span) = e.span() {
            line_column = Some(line_col(self.text, span.start));
            if let (Tree::Toml(doc), false) = (&self.tree, self.root_span == Some(span.clone())) {
                if !locate_in_table(doc, span.start, &mut path) {
                    path.clear();
                }
            }
        }
        let mut message = e.message().trim_end().to_string();
        if let [Seg::Key(kind), Seg::Index(i)] = &path[..] {
            if kind == "joint" {
                if let Some((key, m)) = joint_culprit(self, *i, &message) {
                    // At the key, or at the value of an unknown `type`.
                    let at = At(vec![Seg::Key("joint".into()), Seg::Index(*i), Seg::Key(key.clone())]);
                    let span = match key.as_str() {
                        "type" if m.starts_with("unknown variant") => self.value_span(&at),
                        _ => self.span_of(&at),
                    };
                    line_column = span.map(|s| line_col(self.text, s.start));
                    path.push(Seg::Key(key));
                    message = m;
                }
            }
        }
        let at = At(path);
        let mut err = self.err(&at, message);
        if let Some((line, column)) = line_column {
            err.line = Some(line);
            err.column = Some(column);
        }
        err
    }

    /// A library error raised while building the entry at `at`.
    pub(super) fn stark(&self, at: &At, e: StarkError) -> SceneError {
        self.err(at, e.to_string())
    }
}

/// A JSON syntax or structure error, at the line and column serde_json gives.
pub(super) fn json_error(file: &str, e: &serde_json::Error) -> SceneError {
    let text = e.to_string();
    let message = text
        .rsplit_once(" at line ")
        .map_or(text.as_str(), |(m, _)| m)
        .to_string();
    SceneError {
        file: file.to_string(),
        line: Some(e.line()),
        column: Some(e.column()),
        path: String::new(),
        message,
    }
}

/// Locate an error of a parameter group: a named parameter at its key, anything else at
/// `fallback`.
pub(super) fn param_error(ctx: &Ctx, at: &At, fallback: &str, e: StarkError) -> SceneError {
    match &e {
        StarkError::InvalidParameter { field, .. } => ctx.stark(&at.key(field), e),
        _ => ctx.stark(&at.key(fallback), e),
    }
}
