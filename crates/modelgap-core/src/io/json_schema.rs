//! A small JSON Schema checker for the subset the schemas of modelgap's MCAP channels use:
//! the published Foxglove schemas ([`super::foxglove`]) and modelgap's own flat schemas.
//!
//! Understood keywords: `type` (one of `object`, `array`, `string`, `number`, `integer`,
//! `boolean`, `null`), `properties`, `required`, `additionalProperties` (`true` or
//! `false`), `items` (one schema), `oneOf`, `const`, `enum`, `minimum`, `maximum`; the
//! annotations `title`, `description`, `$comment`, `$schema`, `$id` and `contentEncoding` are
//! read past. Any other keyword is an [`SchemaError::Unsupported`] error, never skipped, so a
//! message is only called valid against a schema this checker fully read. Numbers compare by
//! value (`1` equals `1.0`; `1.0` is an integer).
//!
//! [`Strictness::Complete`] asks more than the schema: every property an object schema
//! declares must be present and no other may be. The Foxglove schemas of
//! `foxglove/schemas` list no `required` fields, but Foxglove's later copies require them
//! all, and a misspelt field would otherwise pass unseen.

use std::fmt::Write as _;

use serde_json::{Map, Value};

/// How much [`check_message`] asks of a message.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strictness {
    /// What the schema says, no more.
    #[default]
    Schema,
    /// As [`Strictness::Schema`], and every object has exactly the properties its schema
    /// declares (when it declares any).
    Complete,
}

/// Why a message does not validate, or why the schema could not be used.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SchemaError {
    /// The message breaks the schema at `path` (a JSON pointer into the message, `""` for
    /// the whole message).
    #[error("at `{path}`: {reason}")]
    Violation {
        /// Where in the message.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The schema uses something this checker does not understand, at `path` (a JSON
    /// pointer into the schema).
    #[error("the schema at `{path}` uses {what}, which this checker does not support")]
    Unsupported {
        /// Where in the schema.
        path: String,
        /// The keyword or form.
        what: String,
    },
}

/// Checks `message` against `schema` (see the [module docs](self) for the subset).
///
/// # Errors
///
/// The first [`SchemaError::Violation`] found, or [`SchemaError::Unsupported`] for a schema
/// outside the subset.
///
/// # Example
///
/// ```
/// # use modelgap_core::io::json_schema::{check_message, Strictness};
/// let schema = serde_json::json!({
///     "type": "object",
///     "properties": { "x": { "type": "number" } },
/// });
/// assert!(check_message(&schema, &serde_json::json!({ "x": 1.5 }), Strictness::Complete).is_ok());
/// let err = check_message(&schema, &serde_json::json!({ "x": "a" }), Strictness::Schema);
/// assert_eq!(err.unwrap_err().to_string(), "at `/x`: expected number, found string \"a\"");
/// ```
pub fn check_message(
    schema: &Value,
    message: &Value,
    strictness: Strictness,
) -> Result<(), SchemaError> {
    Checker { strictness }.check(schema, message, &mut String::new(), &mut String::new())
}

struct Checker {
    strictness: Strictness,
}

const ANNOTATIONS: [&str; 6] = [
    "title",
    "description",
    "$comment",
    "$schema",
    "$id",
    "contentEncoding",
];

impl Checker {
    /// `at` is the JSON pointer into the message, `sat` into the schema; both are restored
    /// before returning.
    fn check(
        &self,
        schema: &Value,
        value: &Value,
        at: &mut String,
        sat: &mut String,
    ) -> Result<(), SchemaError> {
        let Value::Object(schema) = schema else {
            return match schema {
                Value::Bool(true) => Ok(()),
                Value::Bool(false) => Err(violation(at, "no value is allowed here".to_owned())),
                _ => Err(unsupported(
                    sat,
                    "a schema that is not an object or a boolean",
                )),
            };
        };
        for (keyword, arg) in schema {
            match keyword.as_str() {
                k if ANNOTATIONS.contains(&k) => {}
                "type" => check_type(arg, value, at, sat)?,
                "const" => {
                    if !json_equal(arg, value) {
                        return Err(violation(
                            at,
                            format!("expected {}, found {}", short(arg), short(value)),
                        ));
                    }
                }
                "enum" => {
                    let Value::Array(options) = arg else {
                        return Err(unsupported(sat, "`enum` that is not an array"));
                    };
                    if !options.iter().any(|o| json_equal(o, value)) {
                        return Err(violation(
                            at,
                            format!("{} is not one of {}", short(value), short(arg)),
                        ));
                    }
                }
                "minimum" | "maximum" => check_bound(keyword, arg, value, at, sat)?,
                "oneOf" => self.check_one_of(arg, value, at, sat)?,
                "items" => {
                    if let Value::Array(items) = value {
                        for (i, item) in items.iter().enumerate() {
                            let (a, s) = (at.len(), sat.len());
                            let _ = write!(at, "/{i}");
                            sat.push_str("/items");
                            self.check(arg, item, at, sat)?;
                            at.truncate(a);
                            sat.truncate(s);
                        }
                    }
                }
                "properties" => self.check_properties(schema, arg, value, at, sat)?,
                "required" => {
                    let Value::Array(names) = arg else {
                        return Err(unsupported(sat, "`required` that is not an array"));
                    };
                    if let Value::Object(fields) = value {
                        for name in names {
                            let Value::String(name) = name else {
                                return Err(unsupported(sat, "a `required` entry not a string"));
                            };
                            if !fields.contains_key(name) {
                                return Err(violation(
                                    at,
                                    format!("the field `{name}` is missing"),
                                ));
                            }
                        }
                    }
                }
                "additionalProperties" => match arg {
                    Value::Bool(true) => {}
                    Value::Bool(false) => {
                        if let Value::Object(fields) = value {
                            let declared = schema.get("properties").and_then(Value::as_object);
                            if let Some(extra) = fields
                                .keys()
                                .find(|k| declared.is_none_or(|d| !d.contains_key(*k)))
                            {
                                return Err(violation(
                                    at,
                                    format!("the field `{extra}` is not in the schema"),
                                ));
                            }
                        }
                    }
                    _ => return Err(unsupported(sat, "`additionalProperties` as a schema")),
                },
                other => return Err(unsupported(sat, &format!("the keyword `{other}`"))),
            }
        }
        Ok(())
    }

    fn check_properties(
        &self,
        schema: &Map<String, Value>,
        properties: &Value,
        value: &Value,
        at: &mut String,
        sat: &mut String,
    ) -> Result<(), SchemaError> {
        let Value::Object(properties) = properties else {
            return Err(unsupported(sat, "`properties` that is not an object"));
        };
        let Value::Object(fields) = value else {
            // `type` says whether a non-object is allowed.
            return Ok(());
        };
        if self.strictness == Strictness::Complete && !properties.is_empty() {
            if let Some(missing) = properties.keys().find(|k| !fields.contains_key(*k)) {
                return Err(violation(at, format!("the field `{missing}` is missing")));
            }
            let open = schema.get("additionalProperties") == Some(&Value::Bool(true));
            if let Some(extra) = fields.keys().find(|k| !properties.contains_key(*k))
                && !open
            {
                return Err(violation(
                    at,
                    format!("the field `{extra}` is not in the schema"),
                ));
            }
        }
        for (name, field_schema) in properties {
            if let Some(field) = fields.get(name) {
                let (a, s) = (at.len(), sat.len());
                let _ = write!(at, "/{}", pointer_escape(name));
                let _ = write!(sat, "/properties/{}", pointer_escape(name));
                self.check(field_schema, field, at, sat)?;
                at.truncate(a);
                sat.truncate(s);
            }
        }
        Ok(())
    }

    fn check_one_of(
        &self,
        alternatives: &Value,
        value: &Value,
        at: &str,
        sat: &mut String,
    ) -> Result<(), SchemaError> {
        let Value::Array(alternatives) = alternatives else {
            return Err(unsupported(sat, "`oneOf` that is not an array"));
        };
        let mut matched = 0;
        for (i, alternative) in alternatives.iter().enumerate() {
            let s = sat.len();
            let _ = write!(sat, "/oneOf/{i}");
            match self.check(alternative, value, &mut at.to_owned(), sat) {
                Ok(()) => matched += 1,
                Err(e @ SchemaError::Unsupported { .. }) => return Err(e),
                Err(SchemaError::Violation { .. }) => {}
            }
            sat.truncate(s);
        }
        if matched == 1 {
            Ok(())
        } else {
            Err(violation(
                at,
                format!(
                    "{} matches {matched} of the {} alternatives of `oneOf`, not exactly one",
                    short(value),
                    alternatives.len()
                ),
            ))
        }
    }
}

fn check_type(arg: &Value, value: &Value, at: &str, sat: &str) -> Result<(), SchemaError> {
    let Value::String(expected) = arg else {
        return Err(unsupported(sat, "`type` that is not one string"));
    };
    let ok = match expected.as_str() {
        "object" => value.is_object(),
        "array" => value.is_array(),
        "string" => value.is_string(),
        "number" => value.is_number(),
        "integer" => value
            .as_f64()
            .is_some_and(|x| value.is_i64() || value.is_u64() || x.fract() == 0.0),
        "boolean" => value.is_boolean(),
        "null" => value.is_null(),
        other => return Err(unsupported(sat, &format!("the type `{other}`"))),
    };
    if ok {
        Ok(())
    } else {
        Err(violation(
            at,
            format!("expected {expected}, found {}", describe(value)),
        ))
    }
}

fn check_bound(
    keyword: &str,
    bound: &Value,
    value: &Value,
    at: &str,
    sat: &str,
) -> Result<(), SchemaError> {
    let Some(bound) = bound.as_f64() else {
        return Err(unsupported(
            sat,
            &format!("`{keyword}` that is not a number"),
        ));
    };
    let Some(x) = value.as_f64() else {
        return Ok(());
    };
    let (ok, word) = if keyword == "minimum" {
        (x >= bound, "below the minimum")
    } else {
        (x <= bound, "above the maximum")
    };
    if ok {
        Ok(())
    } else {
        Err(violation(at, format!("{} is {word} {bound}", short(value))))
    }
}

/// JSON equality with numbers compared by value.
fn json_equal(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_i64(), y.as_i64()) {
            (Some(i), Some(j)) => i == j,
            _ => x.as_f64() == y.as_f64(),
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| json_equal(a, b))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| json_equal(v, w)))
        }
        _ => a == b,
    }
}

fn describe(value: &Value) -> String {
    let kind = match value {
        Value::Null => "null",
        Value::Bool(_) => "boolean",
        Value::Number(_) => "number",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    };
    match value {
        Value::Array(_) | Value::Object(_) => kind.to_owned(),
        _ => format!("{kind} {}", short(value)),
    }
}

/// A value's JSON text, cut to 40 characters.
fn short(value: &Value) -> String {
    let text = value.to_string();
    match text.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &text[..i]),
        None => text,
    }
}

fn pointer_escape(name: &str) -> String {
    name.replace('~', "~0").replace('/', "~1")
}

fn violation(at: &str, reason: String) -> SchemaError {
    SchemaError::Violation {
        path: at.to_owned(),
        reason,
    }
}

fn unsupported(sat: &str, what: &str) -> SchemaError {
    SchemaError::Unsupported {
        path: sat.to_owned(),
        what: what.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    fn ok(schema: &Value, v: &Value) -> bool {
        check_message(schema, v, Strictness::Schema).is_ok()
    }

    #[test]
    fn types_bounds_and_integers_by_value() {
        let s = json!({ "type": "integer", "minimum": 0, "maximum": 999_999_999 });
        assert!(ok(&s, &json!(0)));
        assert!(ok(&s, &json!(3.0)), "3.0 is an integer in JSON Schema");
        assert!(!ok(&s, &json!(3.5)));
        assert!(!ok(&s, &json!(-1)));
        assert!(!ok(&s, &json!(1_000_000_000)));
        assert!(!ok(&s, &json!("1")));
        assert!(ok(&json!({ "type": "number" }), &json!(1)));
        assert!(!ok(&json!({ "type": "boolean" }), &json!(0)));
    }

    #[test]
    fn nested_objects_and_arrays_name_the_path() {
        let s = json!({
            "type": "object",
            "properties": {
                "points": { "type": "array", "items": {
                    "type": "object",
                    "properties": { "x": { "type": "number" } },
                    "required": ["x"],
                } },
            },
        });
        assert!(ok(&s, &json!({ "points": [{ "x": 1 }, { "x": 2.5 }] })));
        let e = check_message(
            &s,
            &json!({ "points": [{ "x": 1 }, {}] }),
            Strictness::Schema,
        );
        assert_eq!(
            e.unwrap_err(),
            SchemaError::Violation {
                path: "/points/1".into(),
                reason: "the field `x` is missing".into()
            }
        );
        let e = check_message(
            &s,
            &json!({ "points": [{ "x": null }] }),
            Strictness::Schema,
        );
        assert_eq!(
            e.unwrap_err().to_string(),
            "at `/points/0/x`: expected number, found null null"
        );
    }

    #[test]
    fn one_of_const_is_an_enumeration() {
        let s = json!({ "oneOf": [
            { "title": "A", "const": 0 }, { "title": "B", "const": 1 }, { "title": "C", "const": 2 }
        ] });
        assert!(ok(&s, &json!(2)));
        assert!(ok(&s, &json!(2.0)));
        assert!(!ok(&s, &json!(3)));
        assert!(ok(&json!({ "enum": ["a", "b"] }), &json!("b")));
        assert!(!ok(&json!({ "enum": ["a", "b"] }), &json!("c")));
    }

    #[test]
    fn complete_asks_for_every_declared_field_and_no_other() {
        let s = json!({
            "type": "object",
            "properties": { "x": { "type": "number" }, "y": { "type": "number" } },
        });
        let half = json!({ "x": 1 });
        let extra = json!({ "x": 1, "y": 2, "transform": {} });
        assert!(check_message(&s, &half, Strictness::Schema).is_ok());
        assert!(check_message(&s, &extra, Strictness::Schema).is_ok());
        let e = check_message(&s, &half, Strictness::Complete).unwrap_err();
        assert!(e.to_string().contains("`y` is missing"), "{e}");
        let e = check_message(&s, &extra, Strictness::Complete).unwrap_err();
        assert!(
            e.to_string().contains("`transform` is not in the schema"),
            "{e}"
        );
        let closed = json!({
            "type": "object", "properties": { "x": {} }, "additionalProperties": false
        });
        assert!(!ok(&closed, &json!({ "x": 1, "z": 2 })));
    }

    #[test]
    fn unknown_keywords_are_refused_not_skipped() {
        let s = json!({ "type": "object", "properties": { "a": { "$ref": "Other.json" } } });
        let e = check_message(&s, &json!({ "a": 1 }), Strictness::Schema).unwrap_err();
        assert_eq!(
            e,
            SchemaError::Unsupported {
                path: "/properties/a".into(),
                what: "the keyword `$ref`".into()
            }
        );
        let s = json!({ "type": ["number", "null"] });
        assert!(matches!(
            check_message(&s, &json!(1), Strictness::Schema),
            Err(SchemaError::Unsupported { .. })
        ));
    }
}
