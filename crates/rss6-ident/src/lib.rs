//! rss6-ident: offline calibration and identification (issue 6). Work in progress.
#![forbid(unsafe_code)]
