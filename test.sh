#!/usr/bin/env bash
# The project's test command (README: "Tests"). GMP, which the MPFR oracle links, needs m4 to
# build: `.cargo/config.toml` points GMP's build at `.cargo/m4`, which installs it on a fresh
# Debian/Ubuntu machine when run as root.
set -euo pipefail
cd "$(dirname "$0")"

# The library crates must build without std (libm only).
cargo build --quiet -p nlrt-poly -p nlrt-shellmap -p nlrt-accel -p nlrt-baselines --no-default-features --features libm
# Every test of the workspace: unit, integration (oracle, proptest, fuzz-corpus replay), doc tests.
cargo test --workspace "$@"
