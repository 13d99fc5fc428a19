//! Signed packs: an ed25519 signature over the exact bytes of a pack's `manifest.json`, kept in
//! the pack's second entry, `manifest.sig`. The manifest holds the SHA-256 and size of every
//! other file, the commands and the versions, so a valid signature covers the whole pack: a
//! changed file no longer has its hash, and a manifest rewritten to give the new hash no
//! longer has its signature.
//!
//! Keys are files in the standard formats OpenSSL reads and writes: the private key as
//! PKCS #8 PEM (`-----BEGIN PRIVATE KEY-----`), the public key as SubjectPublicKeyInfo PEM
//! (`-----BEGIN PUBLIC KEY-----`). `poser keygen` writes both; `openssl genpkey -algorithm
//! ed25519` and `openssl pkey -pubout` make the same files.
//!
//! | entry | content |
//! |---|---|
//! | `manifest.sig` | JSON: `format` (`poserpack-signature/1`), `algorithm` (`ed25519`), `public_key` (the signer's 32 bytes, base64), `signature` (64 bytes, base64) over `poserpack/1 manifest\n` followed by the bytes of `manifest.json` |
//!
//! The signature in the pack says *which* key signed; only the reader's `--trust KEY` says
//! whether that key is one they trust. Verification is strict (RFC 8032 with the stricter
//! checks of `verify_strict`: no small-order keys, no malleable signatures).

use base64::Engine;
use base64::engine::general_purpose::{STANDARD, STANDARD_NO_PAD};
use ed25519_dalek::pkcs8::{DecodePrivateKey, DecodePublicKey, EncodePublicKey};
use ed25519_dalek::{Signature, Signer, SigningKey, VerifyingKey};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

/// Name of the signature entry (the pack's second entry when present).
pub const SIGNATURE: &str = "manifest.sig";
/// The signature entry's format tag.
pub const SIGNATURE_FORMAT: &str = "poserpack-signature/1";
/// What is signed comes after this prefix, so that a pack signature cannot be replayed as a
/// signature of anything else made with the same key.
const CONTEXT: &[u8] = b"poserpack/1 manifest\n";
/// DER of an ed25519 PKCS #8 v1 `PrivateKeyInfo` up to its 32-byte seed (RFC 8410 §7).
const PKCS8_V1_PREFIX: [u8; 16] = [
    0x30, 0x2e, 0x02, 0x01, 0x00, 0x30, 0x05, 0x06, 0x03, 0x2b, 0x65, 0x70, 0x04, 0x22, 0x04, 0x20,
];
/// Largest key file read (a PEM key is about 120 bytes).
const KEY_FILE_CAP: u64 = 64 << 10;

/// The `manifest.sig` entry.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignatureFile {
    pub format: String,
    pub algorithm: String,
    /// The signer's public key, 32 bytes, base64.
    pub public_key: String,
    /// The signature, 64 bytes, base64.
    pub signature: String,
}

/// Who signed a pack, as found when it was read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SignedBy {
    /// No `manifest.sig`: anyone could have written or changed this pack.
    Unsigned,
    /// A signature that matches the manifest, made with this key (not yet compared with any
    /// trusted key).
    Signed(VerifyingKey),
}

/// A short, stable name of a public key: `SHA256:` and the unpadded base64 of the SHA-256 of
/// its 32 bytes (as `ssh-keygen -l` shows keys).
pub fn fingerprint(k: &VerifyingKey) -> String {
    format!(
        "SHA256:{}",
        STANDARD_NO_PAD.encode(Sha256::digest(k.as_bytes()))
    )
}

fn read_key_text(path: &Path) -> Result<String, String> {
    let bytes = crate::scene::source::read_capped(path, KEY_FILE_CAP)
        .map_err(|r| format!("{}: {}", path.display(), r.reason()))?;
    String::from_utf8(bytes).map_err(|_| {
        format!(
            "{}: not a PEM key file (it is not text)\n  help: make a key with `poser keygen -o KEY` or `openssl genpkey -algorithm ed25519 -out KEY`",
            path.display()
        )
    })
}

/// Read a private key (PKCS #8 PEM, ed25519).
pub fn read_signing_key(path: &Path) -> Result<SigningKey, String> {
    let text = read_key_text(path)?;
    if text.contains("-----BEGIN PUBLIC KEY-----") {
        return Err(format!(
            "{}: a public key; signing needs the private key (the file `poser keygen` wrote without `.pub`)",
            path.display()
        ));
    }
    SigningKey::from_pkcs8_pem(text.trim()).map_err(|e| {
        format!(
            "{}: not an ed25519 private key in PKCS #8 PEM ({e})\n  help: make one with `poser keygen -o KEY` or `openssl genpkey -algorithm ed25519 -out KEY`",
            path.display()
        )
    })
}

/// Read a public key to trust: SubjectPublicKeyInfo PEM (ed25519), or a private key, whose
/// public half is taken.
pub fn read_verifying_key(path: &Path) -> Result<VerifyingKey, String> {
    let text = read_key_text(path)?;
    if text.contains("-----BEGIN PRIVATE KEY-----") {
        return read_signing_key(path).map(|k| k.verifying_key());
    }
    VerifyingKey::from_public_key_pem(text.trim()).map_err(|e| {
        format!(
            "{}: not an ed25519 public key in PEM ({e})\n  help: the signer's `KEY.pub` from `poser keygen`, or `openssl pkey -in KEY -pubout`",
            path.display()
        )
    })
}

/// The `manifest.sig` entry for `manifest` (the exact bytes written as `manifest.json`).
/// Ed25519 signatures are deterministic, so a pack stays byte-stable when signed.
pub fn sign(key: &SigningKey, manifest: &[u8]) -> Vec<u8> {
    let sig = key.sign(&message(manifest));
    let file = SignatureFile {
        format: SIGNATURE_FORMAT.into(),
        algorithm: "ed25519".into(),
        public_key: STANDARD.encode(key.verifying_key().as_bytes()),
        signature: STANDARD.encode(sig.to_bytes()),
    };
    let mut out = serde_json::to_vec_pretty(&file).expect("a signature serializes");
    out.push(b'\n');
    out
}

fn message(manifest: &[u8]) -> Vec<u8> {
    let mut m = Vec::with_capacity(CONTEXT.len() + manifest.len());
    m.extend_from_slice(CONTEXT);
    m.extend_from_slice(manifest);
    m
}

/// Check a `manifest.sig` entry against the manifest's bytes; the key that made it.
pub fn verify(sig_entry: &[u8], manifest: &[u8]) -> Result<VerifyingKey, String> {
    let file: SignatureFile = serde_json::from_slice(sig_entry)
        .map_err(|e| format!("`{SIGNATURE}` is not a pack signature ({e})"))?;
    if file.format != SIGNATURE_FORMAT || file.algorithm != "ed25519" {
        return Err(format!(
            "`{SIGNATURE}`: format `{}`, algorithm `{}`; this poser reads `{SIGNATURE_FORMAT}`, `ed25519`",
            file.format, file.algorithm
        ));
    }
    let key: [u8; 32] = STANDARD
        .decode(&file.public_key)
        .ok()
        .and_then(|b| b.try_into().ok())
        .ok_or_else(|| format!("`{SIGNATURE}`: the public key is not 32 bytes of base64"))?;
    let sig: [u8; 64] = STANDARD
        .decode(&file.signature)
        .ok()
        .and_then(|b| b.try_into().ok())
        .ok_or_else(|| format!("`{SIGNATURE}`: the signature is not 64 bytes of base64"))?;
    let key = VerifyingKey::from_bytes(&key)
        .map_err(|_| format!("`{SIGNATURE}`: the public key is not an ed25519 point"))?;
    key.verify_strict(&message(manifest), &Signature::from_bytes(&sig))
        .map_err(|_| {
            format!(
                "the signature in `{SIGNATURE}` does not match `manifest.json`: the pack was changed after it was signed (by key {})",
                fingerprint(&key)
            )
        })?;
    Ok(key)
}

/// What a reader asks of a pack's signature: `trusted` empty accepts any pack and says whether
/// it is signed; otherwise the pack must be signed by one of these keys.
pub fn judge(signed: &SignedBy, trusted: &[VerifyingKey]) -> Result<String, String> {
    match (signed, trusted.is_empty()) {
        (SignedBy::Unsigned, true) => Ok(
            "unsigned: nothing shows who made this pack or that it is unchanged since (sign with `poser pack --sign KEY`; check with `--trust KEY.pub`)".into(),
        ),
        (SignedBy::Unsigned, false) => Err(format!(
            "the pack is unsigned, and --trust asks for a signature by {}; refused",
            names(trusted)
        )),
        (SignedBy::Signed(k), true) => Ok(format!(
            "signed by key {} (not checked against a key you trust: give --trust KEY.pub)",
            fingerprint(k)
        )),
        (SignedBy::Signed(k), false) if trusted.contains(k) => {
            Ok(format!("signed by trusted key {}", fingerprint(k)))
        }
        (SignedBy::Signed(k), false) => Err(format!(
            "the pack is signed by key {}, not by {} that --trust names; refused",
            fingerprint(k),
            names(trusted)
        )),
    }
}

fn names(keys: &[VerifyingKey]) -> String {
    let f: Vec<String> = keys.iter().map(fingerprint).collect();
    if f.len() == 1 {
        format!("key {}", f[0])
    } else {
        format!("any of keys {}", f.join(", "))
    }
}

/// Make a key pair: `path` (private, PKCS #8 PEM, mode 0600) and `path.pub` (public, PEM).
/// Neither may exist already. Returns the public key.
pub fn keygen(path: &Path) -> Result<VerifyingKey, String> {
    let public = pub_path(path);
    for p in [path, public.as_path()] {
        if std::fs::symlink_metadata(p).is_ok() {
            return Err(format!(
                "{} exists; a key is never overwritten (choose another name)",
                p.display()
            ));
        }
    }
    let mut seed = [0u8; 32];
    getrandom::fill(&mut seed).map_err(|e| format!("no random bytes from the system: {e}"))?;
    let key = SigningKey::from_bytes(&seed);
    // PKCS #8 version 1 (the seed only), byte for byte what `openssl genpkey -algorithm
    // ed25519` writes: OpenSSL 3.0 cannot read the version 2 form with the public key inside.
    let mut der = PKCS8_V1_PREFIX.to_vec();
    der.extend_from_slice(&seed);
    seed.fill(0);
    let private = format!(
        "-----BEGIN PRIVATE KEY-----\n{}\n-----END PRIVATE KEY-----\n",
        STANDARD.encode(&der)
    );
    der.fill(0);
    let public_pem = key
        .verifying_key()
        .to_public_key_pem(ed25519_dalek::pkcs8::spki::der::pem::LineEnding::LF)
        .map_err(|e| e.to_string())?;
    write_new(path, private.as_bytes(), 0o600)?;
    if let Err(e) = write_new(&public, public_pem.as_bytes(), 0o644) {
        let _ = std::fs::remove_file(path);
        return Err(e);
    }
    Ok(key.verifying_key())
}

/// The public key's file beside a private key's: `KEY.pub`.
pub fn pub_path(path: &Path) -> std::path::PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".pub");
    s.into()
}

fn write_new(path: &Path, bytes: &[u8], mode: u32) -> Result<(), String> {
    use std::io::Write;
    let mut o = std::fs::OpenOptions::new();
    o.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.mode(mode);
    }
    #[cfg(not(unix))]
    let _ = mode;
    o.open(path)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()))
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(b: u8) -> SigningKey {
        SigningKey::from_bytes(&[b; 32])
    }

    #[test]
    fn a_signature_verifies_only_its_own_manifest() {
        let m = br#"{"format":"poserpack/1"}"#;
        let s = sign(&key(1), m);
        assert_eq!(verify(&s, m).unwrap(), key(1).verifying_key());
        assert_eq!(s, sign(&key(1), m), "deterministic");
        let e = verify(&s, br#"{"format":"poserpack/2"}"#).unwrap_err();
        assert!(e.contains("changed after it was signed"), "{e}");
        // Another key's signature with this key's name on it.
        let mut f: SignatureFile = serde_json::from_slice(&s).unwrap();
        let other: SignatureFile = serde_json::from_slice(&sign(&key(2), m)).unwrap();
        f.signature = other.signature;
        let e = verify(&serde_json::to_vec(&f).unwrap(), m).unwrap_err();
        assert!(e.contains("does not match"), "{e}");
        assert!(
            verify(b"not json", m)
                .unwrap_err()
                .contains("not a pack signature")
        );
    }

    #[test]
    fn trust_is_judged_by_key() {
        let (a, b) = (key(1).verifying_key(), key(2).verifying_key());
        assert!(
            judge(&SignedBy::Unsigned, &[])
                .unwrap()
                .starts_with("unsigned")
        );
        assert!(
            judge(&SignedBy::Unsigned, &[a])
                .unwrap_err()
                .contains("unsigned")
        );
        assert!(
            judge(&SignedBy::Signed(a), &[a])
                .unwrap()
                .contains("trusted")
        );
        assert!(judge(&SignedBy::Signed(a), &[b, a]).is_ok());
        let e = judge(&SignedBy::Signed(a), &[b]).unwrap_err();
        assert!(
            e.contains(&fingerprint(&a)) && e.contains(&fingerprint(&b)),
            "{e}"
        );
    }

    #[test]
    fn keygen_writes_pem_files_that_read_back() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("k");
        let v = keygen(&p).unwrap();
        let sk = read_signing_key(&p).unwrap();
        assert_eq!(sk.verifying_key(), v);
        assert_eq!(read_verifying_key(&pub_path(&p)).unwrap(), v);
        assert_eq!(
            read_verifying_key(&p).unwrap(),
            v,
            "a private key is trusted as its public half"
        );
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o600);
        }
        assert!(keygen(&p).unwrap_err().contains("never overwritten"));
        let e = read_signing_key(&pub_path(&p)).unwrap_err();
        assert!(e.contains("a public key"), "{e}");
        std::fs::write(d.path().join("junk"), "hello").unwrap();
        assert!(read_verifying_key(&d.path().join("junk")).is_err());
    }
}
