"""``sb3-aac export``: write a trained model's policy as a ``.aacp`` file for a runtime without torch; ``sb3-aac c-header``:
where the C runtime that reads it (``aacp.h``) is installed."""

from __future__ import annotations

import argparse
from typing import Any

from sb3_aac.cli.arguments import CliError, add_trust_argument, input_file, output_file
from sb3_aac.cli.envs import PROFILE_ENV_IDS
from sb3_aac.cli.models import load_model, model_matches_profile


def add_export_command(add: Any) -> None:
    """Add ``export`` through ``add(name, help, example)``."""
    export = add(
        "export",
        "write MODEL's policy as plain arrays + JSON for a runtime without torch (sb3_aac.runtime.RuntimePolicy, C++)",
        "sb3-aac export runs/rbf/model.zip dribbler.aacp",
    )
    export.add_argument("model", metavar="MODEL", help="a model.zip (SarsaAAC, HybridPPO, PDQN or MPDQN)")
    export.add_argument("out", metavar="OUT", help="the policy file to write (.aacp); format: docs/export-format.md")
    add_trust_argument(export)
    export.set_defaults(func=cmd_export)


def cmd_export(args: argparse.Namespace) -> None:
    from sb3_aac import RuntimePolicy, export_policy

    source = input_file(args.model, (".zip",), "MODEL")
    out = output_file(args.out, (".aacp",), "OUT")
    model = load_model(source, args.trust)
    matches = [p for p in PROFILE_ENV_IDS if model_matches_profile(model, p)]
    metadata = {"env_id": PROFILE_ENV_IDS[matches[0]]} if matches else {}
    try:
        path = export_policy(model, out, metadata=metadata)
    except OSError as error:
        raise CliError(f"cannot write {out}: {error.strerror or error}") from None
    except ValueError as error:  # a model export cannot carry
        raise CliError(f"cannot export {source}: {error}") from None
    policy = RuntimePolicy.load(path)
    print(f"wrote {path} ({path.stat().st_size} bytes): {policy!r}")
    print("load it with: from sb3_aac.runtime import RuntimePolicy; RuntimePolicy.load(path).act(obs)  (numpy only)")


def add_c_header_command(add: Any) -> None:
    """Add ``c-header`` through ``add(name, help, example)``."""
    header = add(
        "c-header",
        "print the path of aacp.h, the C99 header that loads an exported .aacp policy in a C or C++ agent",
        'c++ -I "$(dirname "$(sb3-aac c-header)")" agent.cpp   # docs: Using a policy in a C++ agent',
    )
    header.set_defaults(func=cmd_c_header)


def cmd_c_header(args: argparse.Namespace) -> None:
    from sb3_aac.runtime.c import header_path

    print(header_path())
