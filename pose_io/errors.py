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

    Only a SystemExit with a signal's status (128 + the signal, as the command line's SIGTERM handler raises) counts;
    a library's own ``sys.exit(0)`` turned into an error stays that error.

    Args:
        exc: the exception just caught.

    Raises:
        SystemExit | KeyboardInterrupt: the interrupt found among ``exc``'s causes and contexts.
    """
    seen: set[int] = set()
    pending = [exc.__cause__, exc.__context__]
    while pending:
        link = pending.pop()
        if link is None or id(link) in seen:
            continue
        seen.add(id(link))
        if isinstance(link, KeyboardInterrupt) or (
                isinstance(link, SystemExit) and isinstance(link.code, int) and link.code >= 128):
            raise link
        pending += [link.__cause__, link.__context__]
