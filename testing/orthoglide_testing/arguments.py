"""The command lines of the scripts and benchmarks: one parser maker."""

import argparse


def script_parser(doc, *options):
    """
    Return a script's parser: ``doc``'s first paragraph, then ``options``.

    Each option a ``(flag, default, help)`` row: its type is the
    default's (int, float or str), the default is said after the help.
    """
    parser = argparse.ArgumentParser(
        description=doc.strip().split('\n\n')[0])
    for flag, default, text in options:
        parser.add_argument(flag, type=type(default), default=default,
                            help=f'{text} (default %(default)s)')
    return parser
