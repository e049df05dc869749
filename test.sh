#!/usr/bin/env bash
# The project's test command (README: "Tests"). On a fresh machine it first installs what the
# MPFR oracle's build needs and the machine lacks: GMP's configure needs `m4`.
set -euo pipefail
cd "$(dirname "$0")"

if ! command -v m4 >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "test.sh: installing m4 (needed to build GMP for the MPFR oracle)" >&2
        apt-get update -qq >/dev/null
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq m4 >/dev/null
    else
        echo "test.sh: m4 is required to build GMP (the oracle's dependency); install it (e.g. apt-get install m4)" >&2
        exit 1
    fi
fi

# The library crates must build without std (libm only).
cargo build --quiet -p nlrt-poly -p nlrt-shellmap -p nlrt-accel -p nlrt-baselines --no-default-features --features libm
# Every test of the workspace: unit, integration (oracle, proptest, fuzz-corpus replay), doc tests.
cargo test --workspace "$@"
