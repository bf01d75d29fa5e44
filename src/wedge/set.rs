//! One `--set PATH=V1,V2,…` of `polyphase wedge`: a dotted path into the scene file and the
//! values it takes, and how a value is written into the file's TOML tree.

use std::fmt;

use anyhow::{bail, Result};
use toml::Value;

/// A parsed `--set`: where in the scene file, and the values of the wedge's axis.
#[derive(Clone, Debug, PartialEq)]
pub struct SetAxis {
    /// The argument as given, for error messages.
    pub arg: String,
    /// Dotted path, e.g. `phases.oil.viscosity` or `time.end`.
    pub path: String,
    pub values: Vec<Value>,
}

impl SetAxis {
    /// Parses `PATH=V1,V2,…`. A value is read as TOML (`0.1`, `true`, `"text"`, `[1, 2]`) and,
    /// when it is not valid TOML, taken as a bare string (`contour`).
    pub fn parse(arg: &str) -> Result<SetAxis> {
        let Some((path, list)) = arg.split_once('=') else {
            bail!("--set {arg}: expected PATH=VALUE[,VALUE…], e.g. phases.oil.viscosity=0.01,0.1");
        };
        let path = path.trim();
        if path.is_empty() || path.split('.').any(|s| s.trim().is_empty()) {
            bail!("--set {arg}: the path '{path}' has an empty part");
        }
        let values: Vec<Value> = split_top_level(list)
            .into_iter()
            .map(|v| parse_value(v.trim()))
            .collect();
        if values
            .iter()
            .any(|v| matches!(v, Value::String(s) if s.is_empty()))
        {
            bail!("--set {arg}: empty value in the list");
        }
        Ok(SetAxis {
            arg: arg.to_string(),
            path: path.to_string(),
            values,
        })
    }
}

/// Splits at the commas that are not inside brackets or quotes, so `[1, 2],[3, 4]` is two
/// values.
fn split_top_level(list: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut quote, mut start) = (0i32, None::<char>, 0);
    for (i, c) in list.char_indices() {
        match (c, quote) {
            ('"' | '\'', None) => quote = Some(c),
            (q, Some(open)) if q == open => quote = None,
            (_, Some(_)) => {}
            ('[' | '{', None) => depth += 1,
            (']' | '}', None) => depth -= 1,
            (',', None) if depth == 0 => {
                parts.push(&list[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&list[start..]);
    parts
}

/// A value as TOML, or the text itself as a string when it is not TOML.
fn parse_value(text: &str) -> Value {
    toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| Value::String(text.to_string()))
}

/// Writes `value` at the dotted `path` of `doc`. A part names a table key, an array element by
/// index, or the element of an array of tables whose `name` it is (`phases.oil`). The last
/// part may add a key to an existing table (validation then rejects keys the format lacks);
/// every earlier part must exist.
pub fn set_path(doc: &mut Value, path: &str, value: Value) -> Result<()> {
    let parts: Vec<&str> = path.split('.').map(str::trim).collect();
    let mut here = doc;
    for (k, part) in parts.iter().enumerate() {
        let last = k + 1 == parts.len();
        let walked = Walked(&parts[..k]);
        here = match here {
            Value::Table(table) => {
                if last {
                    table.insert(part.to_string(), value);
                    return Ok(());
                }
                if !table.contains_key(*part) {
                    bail!(
                        "{walked} has no '{part}' (it has: {})",
                        table.keys().cloned().collect::<Vec<_>>().join(", ")
                    );
                }
                &mut table[*part]
            }
            Value::Array(items) => {
                let names: Vec<String> = items
                    .iter()
                    .filter_map(|v| v.get("name").and_then(Value::as_str).map(String::from))
                    .collect();
                let index = match part.parse::<usize>() {
                    Ok(i) if i < items.len() => i,
                    Ok(i) => bail!("{walked} has {} entries, no index {i}", items.len()),
                    Err(_) => match names.iter().position(|n| n == part) {
                        Some(i) => i,
                        None => bail!(
                            "{walked} has no entry named '{part}' (names: {})",
                            names.join(", ")
                        ),
                    },
                };
                if last {
                    items[index] = value;
                    return Ok(());
                }
                &mut items[index]
            }
            _ => bail!("{walked} is a single value, it has no '{part}'"),
        };
    }
    Ok(())
}

/// The part of a path walked so far, for messages (`the scene` at the root).
struct Walked<'a>(&'a [&'a str]);

impl fmt::Display for Walked<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0.is_empty() {
            true => write!(f, "the scene"),
            false => write!(f, "'{}'", self.0.join(".")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc() -> Value {
        toml::from_str(
            "resolution = 32\n[time]\nend = 1.0\n[[phases]]\nname = \"air\"\nviscosity = 1e-5\n\
             [[phases]]\nname = \"oil\"\nviscosity = 0.1\n",
        )
        .expect("test document")
    }

    #[test]
    fn values_are_toml_or_bare_strings() {
        let s = SetAxis::parse("a.b=0.01, 2,true,contour,[1, 2],\"x,y\"").expect("parses");
        assert_eq!(s.path, "a.b");
        assert_eq!(
            s.values,
            vec![
                Value::Float(0.01),
                Value::Integer(2),
                Value::Boolean(true),
                Value::String("contour".into()),
                Value::Array(vec![Value::Integer(1), Value::Integer(2)]),
                Value::String("x,y".into()),
            ]
        );
        assert!(SetAxis::parse("novalue").is_err());
        assert!(SetAxis::parse("a..b=1").is_err());
        assert!(SetAxis::parse("a=1,,2").is_err());
    }

    #[test]
    fn paths_reach_tables_and_named_array_entries() {
        let mut d = doc();
        set_path(&mut d, "phases.oil.viscosity", Value::Float(1.0)).expect("named entry");
        set_path(&mut d, "phases.0.viscosity", Value::Float(2.0)).expect("index");
        set_path(&mut d, "time.end", Value::Float(3.0)).expect("table key");
        assert_eq!(d["phases"][1]["viscosity"], Value::Float(1.0));
        assert_eq!(d["phases"][0]["viscosity"], Value::Float(2.0));
        assert_eq!(d["time"]["end"], Value::Float(3.0));
    }

    #[test]
    fn bad_paths_name_the_missing_part() {
        let mut d = doc();
        let err = |p: &str| {
            set_path(&mut d.clone(), p, Value::Integer(1))
                .expect_err(p)
                .to_string()
        };
        assert!(err("phases.water.viscosity").contains("no entry named 'water'"));
        assert!(err("phases.5.viscosity").contains("no index 5"));
        assert!(err("solver.resolution").contains("the scene has no 'solver'"));
        assert!(err("resolution.x").contains("'resolution' is a single value"));
        set_path(&mut d, "time.frames", Value::Integer(4)).expect("a new key in a table");
    }
}
