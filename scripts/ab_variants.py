"""The kernel variants an A/B script compares (scripts/instructions_ab.py, stage_ab.py).

A variant is NAME=GLSL_DIR, optionally followed by @BINARY (its own `vkvcm`, for a change
of the Rust side too) and |ARGS (extra `vkvcm render` arguments). Its shaders are compiled
at run time from GLSL_DIR (VKVCM_GLSL_DIR), so a variant of the kernels alone needs no
build of its own.
"""

import os
import shlex
from collections import namedtuple

Variant = namedtuple("Variant", "name glsl binary extra")

HELP = "NAME=GLSL_DIR[@BINARY][|render args]; the first is the base"


def parse_variant(text, default_binary):
    """The Variant that `text` (NAME=GLSL_DIR[@BINARY][|ARGS]) describes."""
    name, _, rest = text.partition("=")
    dirs, _, extra = rest.partition("|")
    glsl, _, binary = dirs.partition("@")
    if not name or not glsl:
        raise SystemExit(f"variant {text!r}: expected NAME=GLSL_DIR[@BINARY][|ARGS]")
    return Variant(name, os.path.abspath(glsl), binary or default_binary, shlex.split(extra))


def variant_env(variant):
    """The environment a variant's `vkvcm` runs in."""
    return dict(os.environ, VKVCM_GLSL_DIR=variant.glsl)
