"""The one exception type for problems a user can cause (bad files, wrong sizes, missing data).

Commands catch it and print its message as a single line with a non-zero exit; anything else is a bug
and keeps its traceback.
"""


class InputError(ValueError):
    """Bad user input: the message names the file or value and the problem, in one line."""


def raise_if_interrupted(exc: BaseException) -> None:
    """Re-raise the SystemExit or KeyboardInterrupt that ``exc`` wraps, if it wraps one.

    A signal handled while an extension module imports or runs (a SIGTERM whose handler raises SystemExit, a Ctrl-C)
    can surface as an ordinary error, e.g. ``ImportError: initialization failed`` caused by the SystemExit. Code that
    catches ``Exception`` to fall back to a slower path calls this first, so that stopping the command still stops it.

    Args:
        exc: the exception just caught.

    Raises:
        SystemExit | KeyboardInterrupt: the interrupt found in ``exc``'s cause or context chain.
    """
    seen: set[int] = set()
    link = exc.__cause__ or exc.__context__
    while link is not None and id(link) not in seen:
        if isinstance(link, (SystemExit, KeyboardInterrupt)):
            raise link
        seen.add(id(link))
        link = link.__cause__ or link.__context__
