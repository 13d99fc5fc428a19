//! The derive on real structs: one constant per field, named as the field, valued as the
//! TOML key (serde's and schemars' `rename`, `rename_all`, raw identifiers), and `KEYS`.
#![allow(dead_code)]

use poser_keys::Keys;

#[derive(Keys)]
#[serde(deny_unknown_fields)]
struct Light {
    name: Option<String>,
    #[serde(rename = "type")]
    kind: Option<u8>,
    beam_angle: f64,
    r#mount: u8,
}

#[derive(Keys)]
#[serde(rename_all = "kebab-case")]
struct Kebab {
    beam_angle: f64,
    #[serde(rename = "exact_key")]
    renamed: f64,
    #[schemars(rename = "from_schemars")]
    #[serde(rename = "from_serde")]
    both: f64,
}

#[derive(Keys)]
#[serde(rename_all = "snake_case")]
struct Generic<T> {
    value_of: T,
}

#[test]
fn constants_are_the_keys() {
    assert_eq!(Light::name, "name");
    assert_eq!(Light::kind, "type");
    assert_eq!(Light::beam_angle, "beam_angle");
    assert_eq!(Light::mount, "mount");
    assert_eq!(Light::KEYS, ["name", "type", "beam_angle", "mount"]);
}

#[test]
fn rename_all_and_rename() {
    assert_eq!(Kebab::beam_angle, "beam-angle");
    assert_eq!(Kebab::renamed, "exact_key");
    assert_eq!(Kebab::both, "from_schemars");
    assert_eq!(Generic::<u8>::value_of, "value_of");
    assert_eq!(Generic::<()>::KEYS, ["value_of"]);
}

#[test]
fn constants_are_usable_in_const_context() {
    const K: &str = Light::kind;
    const N: usize = Light::KEYS.len();
    assert_eq!((K, N), ("type", 4));
}
