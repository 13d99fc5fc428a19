//! Cross-backend agreement: locate targets in rendered images, compare them with the exact
//! ground truth and with each other, and write the `poser compare` report.

pub mod detect;
