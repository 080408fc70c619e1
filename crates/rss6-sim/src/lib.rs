//! rss6-sim: the physics plant that plays the real robot (issue 5). Work in progress.
#![forbid(unsafe_code)]
