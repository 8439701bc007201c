//! `results.csv`: one row per record, one column per scalar field of any record.

use super::records::Record;
use serde_json::Value;
use std::collections::BTreeSet;

/// Flattens `records` to CSV: the union of their scalar fields (not objects or arrays) as
/// columns, sorted by name; a field a record lacks, or that is `null`, is an empty cell.
///
/// # Errors
/// When a record cannot be represented as JSON (never for these types).
pub(super) fn to_csv(records: &[Record]) -> serde_json::Result<String> {
    let rows = records
        .iter()
        .map(Record::to_value)
        .collect::<serde_json::Result<Vec<Value>>>()?;
    Ok(values_to_csv(&rows))
}

/// [`to_csv`] of JSON objects.
fn values_to_csv(records: &[Value]) -> String {
    let mut keys = BTreeSet::new();
    for r in records {
        if let Some(o) = r.as_object() {
            for (k, v) in o {
                if !v.is_object() && !v.is_array() {
                    keys.insert(k.as_str());
                }
            }
        }
    }
    let keys: Vec<&str> = keys.into_iter().collect();
    let mut s = keys.join(",");
    s.push('\n');
    for r in records {
        let row: Vec<String> = keys
            .iter()
            .map(|k| match &r[*k] {
                Value::Null => String::new(),
                Value::String(x) => csv_field(x),
                other => csv_field(&other.to_string()),
            })
            .collect();
        s += &row.join(",");
        s.push('\n');
    }
    s
}

/// One cell: quoted, with doubled quotes, when it holds a comma, quote or newline.
fn csv_field(x: &str) -> String {
    if x.contains([',', '"', '\n']) {
        format!("\"{}\"", x.replace('"', "\"\""))
    } else {
        x.to_owned()
    }
}
