//! `poser keygen`: make an ed25519 key pair for signing packs (`poser pack --sign KEY`,
//! `poser rerun --trust KEY.pub`). The files are the standard PEM formats OpenSSL reads and
//! writes (`src/pack/sign.rs`), so a key made with `openssl genpkey -algorithm ed25519` works
//! the same; this command is there so that signing needs nothing but poser.
use super::CliError;
use crate::pack::sign;
use std::path::PathBuf;

/// The arguments of `poser keygen`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The private key to write (PKCS #8 PEM, readable only by you); the public key goes
    /// beside it as `KEY.pub`. Neither may exist.
    #[arg(short, long, value_name = "KEY")]
    pub out: PathBuf,
}

pub fn run(args: &Args) -> Result<(), CliError> {
    let key = sign::keygen(&args.out).map_err(CliError::Failed)?;
    println!(
        "wrote {} (private: keep it to yourself) and {} (public: give it to whoever reruns your packs)\nkey {}",
        args.out.display(),
        sign::pub_path(&args.out).display(),
        sign::fingerprint(&key)
    );
    Ok(())
}
