//! `#[derive(Keys)]`: the TOML key of every field of a scene-format struct as an associated
//! constant named as the field, so that a key is spelled once (the field, with serde's
//! `rename`/`rename_all`) and every reader and writer names it through a compiler-checked
//! constant: `format::types::Light::beam_angle == "beam_angle"`,
//! `format::types::Light::kind == "type"`, and `Light::KEYS` lists them all in order.
//!
//! Honoured: `#[serde(rename = "…")]` and `#[schemars(rename = "…")]` on a field (schemars
//! wins, as it does in the schema), `#[serde(rename_all = "…")]` / `#[schemars(rename_all =
//! "…")]` on the struct (serde's case names), raw identifiers (`r#type` → `type`). Refused
//! with a compile error, since the keys would no longer be the fields': `flatten`, `skip`,
//! split `rename(serialize = …, deserialize = …)`, tuple and unit structs, enums, unions.

use proc_macro::TokenStream;
use quote::{format_ident, quote};
use syn::{Attribute, Data, DeriveInput, Fields, LitStr, parse_macro_input};

#[proc_macro_derive(Keys, attributes(serde, schemars))]
pub fn derive_keys(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    match expand(&input) {
        Ok(t) => t.into(),
        Err(e) => e.to_compile_error().into(),
    }
}

fn expand(input: &DeriveInput) -> syn::Result<proc_macro2::TokenStream> {
    let Data::Struct(data) = &input.data else {
        return Err(syn::Error::new_spanned(
            &input.ident,
            "`Keys` is for structs with named fields (a table's keys)",
        ));
    };
    let Fields::Named(fields) = &data.fields else {
        return Err(syn::Error::new_spanned(
            &input.ident,
            "`Keys` is for structs with named fields (a table's keys)",
        ));
    };
    let rename_all = container_rename_all(&input.attrs)?;
    let mut consts = Vec::new();
    let mut keys = Vec::new();
    for f in &fields.named {
        let ident = f.ident.as_ref().expect("named field");
        let name = unraw(&ident.to_string());
        let key = match field_rename(&f.attrs)? {
            Some(k) => k,
            None => match &rename_all {
                Some((rule, lit)) => {
                    apply_rule(rule, &name).ok_or_else(|| unknown_rule(lit, rule))?
                }
                None => name.clone(),
            },
        };
        let c = format_ident!("{}", name, span = ident.span());
        let doc = format!("The TOML key `{key}` (field `{name}`).");
        consts.push(quote! {
            #[doc = #doc]
            pub const #c: &'static str = #key;
        });
        keys.push(key);
    }
    let ty = &input.ident;
    let (imp, tys, wh) = input.generics.split_for_impl();
    let keys_doc = format!("Every TOML key of `{ty}`, in field order.");
    Ok(quote! {
        #[allow(non_upper_case_globals, dead_code)]
        impl #imp #ty #tys #wh {
            #(#consts)*
            #[doc = #keys_doc]
            pub const KEYS: &'static [&'static str] = &[#(#keys),*];
        }
    })
}

/// The value `read` finds in the `serde` and `schemars` attributes, schemars' over serde's
/// (as in the schema). `read` sees each nested item and returns `Some` for the one it wants.
fn schemars_over_serde<T>(
    attrs: &[Attribute],
    mut read: impl FnMut(&syn::meta::ParseNestedMeta) -> syn::Result<Option<T>>,
) -> syn::Result<Option<T>> {
    let mut out = None;
    for (tool, a) in tool_attrs(attrs) {
        let mut found = None;
        a.parse_nested_meta(|m| {
            if let Some(v) = read(&m)? {
                found = Some(v);
            }
            Ok(())
        })?;
        if found.is_some() && (out.is_none() || tool == "schemars") {
            out = found;
        }
    }
    Ok(out)
}

/// `rename_all = "…"` of the struct, schemars' over serde's.
fn container_rename_all(attrs: &[Attribute]) -> syn::Result<Option<(String, LitStr)>> {
    schemars_over_serde(attrs, |m| {
        if m.path.is_ident("rename_all") {
            let lit: LitStr = m.value()?.parse()?;
            return Ok(Some((lit.value(), lit)));
        }
        skip_value(m)?;
        Ok(None)
    })
}

/// `rename = "…"` of a field, schemars' over serde's; `flatten`, `skip` and split renames are
/// refused.
fn field_rename(attrs: &[Attribute]) -> syn::Result<Option<String>> {
    schemars_over_serde(attrs, |m| {
        let p = &m.path;
        if p.is_ident("rename") {
            if m.input.peek(syn::token::Paren) {
                return Err(m.error("`Keys` needs one key: a plain `rename = \"…\"`"));
            }
            return Ok(Some(m.value()?.parse::<LitStr>()?.value()));
        }
        if ["flatten", "skip", "skip_deserializing", "skip_serializing"]
            .iter()
            .any(|w| p.is_ident(w))
        {
            return Err(m.error("`Keys` cannot name the keys of a flattened or skipped field"));
        }
        skip_value(m)?;
        Ok(None)
    })
}

fn tool_attrs(attrs: &[Attribute]) -> impl Iterator<Item = (&'static str, &Attribute)> {
    attrs.iter().filter_map(|a| {
        if a.path().is_ident("serde") {
            Some(("serde", a))
        } else if a.path().is_ident("schemars") {
            Some(("schemars", a))
        } else {
            None
        }
    })
}

/// Steps over an attribute item this derive does not read (`deny_unknown_fields`,
/// `title = "…"`, `default`, `with(…)`).
fn skip_value(m: &syn::meta::ParseNestedMeta) -> syn::Result<()> {
    if m.input.peek(syn::Token![=]) {
        m.value()?.parse::<syn::Expr>()?;
    } else if m.input.peek(syn::token::Paren) {
        let content;
        syn::parenthesized!(content in m.input);
        content.parse::<proc_macro2::TokenStream>()?;
    }
    Ok(())
}

fn unknown_rule(lit: &LitStr, rule: &str) -> syn::Error {
    syn::Error::new(
        lit.span(),
        format!(
            "unknown `rename_all` rule `{rule}` (serde's: lowercase, UPPERCASE, PascalCase, camelCase, snake_case, SCREAMING_SNAKE_CASE, kebab-case, SCREAMING-KEBAB-CASE)"
        ),
    )
}

/// `r#type` → `type`.
fn unraw(s: &str) -> String {
    s.strip_prefix("r#").unwrap_or(s).to_string()
}

/// serde's `rename_all` rule applied to a field name (a field is snake_case already).
fn apply_rule(rule: &str, field: &str) -> Option<String> {
    let pascal = || {
        field
            .split('_')
            .map(|w| {
                let mut c = w.chars();
                c.next()
                    .map(|f| f.to_uppercase().chain(c).collect::<String>())
                    .unwrap_or_default()
            })
            .collect::<String>()
    };
    Some(match rule {
        "lowercase" | "snake_case" => field.to_string(),
        "UPPERCASE" | "SCREAMING_SNAKE_CASE" => field.to_ascii_uppercase(),
        "PascalCase" => pascal(),
        "camelCase" => {
            let p = pascal();
            let mut c = p.chars();
            c.next()
                .map(|f| f.to_lowercase().chain(c).collect())
                .unwrap_or_default()
        }
        "kebab-case" => field.replace('_', "-"),
        "SCREAMING-KEBAB-CASE" => field.replace('_', "-").to_ascii_uppercase(),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_follow_serde_for_field_names() {
        let r = |rule| apply_rule(rule, "beam_angle").unwrap();
        assert_eq!(r("snake_case"), "beam_angle");
        assert_eq!(r("lowercase"), "beam_angle");
        assert_eq!(r("UPPERCASE"), "BEAM_ANGLE");
        assert_eq!(r("SCREAMING_SNAKE_CASE"), "BEAM_ANGLE");
        assert_eq!(r("PascalCase"), "BeamAngle");
        assert_eq!(r("camelCase"), "beamAngle");
        assert_eq!(r("kebab-case"), "beam-angle");
        assert_eq!(r("SCREAMING-KEBAB-CASE"), "BEAM-ANGLE");
        assert_eq!(apply_rule("Title Case", "x"), None);
        assert_eq!(unraw("r#type"), "type");
        assert_eq!(unraw("kind"), "kind");
    }

    #[test]
    fn refuses_what_would_hide_a_key() {
        for src in [
            "struct A { #[serde(flatten)] b: B }",
            "struct A { #[serde(skip)] b: B }",
            "struct A { #[serde(rename(serialize = \"x\"))] b: B }",
            "#[serde(rename_all = \"Title Case\")] struct A { b: B }",
            "struct A(u8);",
            "enum A { B }",
        ] {
            let input: DeriveInput = syn::parse_str(src).unwrap();
            assert!(expand(&input).is_err(), "{src}");
        }
        let ok: DeriveInput =
            syn::parse_str("#[schemars(deny_unknown_fields, title = \"t\")] struct A { #[serde(default, rename = \"type\")] kind: u8 }")
                .unwrap();
        let out = expand(&ok).unwrap().to_string();
        assert!(out.contains("\"type\""), "{out}");
    }
}
