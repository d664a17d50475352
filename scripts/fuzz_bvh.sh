#!/usr/bin/env bash
# Kept for old instructions: fuzzes the BVH parser only (see scripts/fuzz.sh).
#   scripts/fuzz_bvh.sh [SECONDS]
exec bash "$(dirname "$0")/fuzz.sh" "${1:-60}" bvh
