"""The one exception type for problems a user can cause (bad files, wrong sizes, missing data).

Commands catch it and print its message as a single line with a non-zero exit; anything else is a bug
and keeps its traceback.
"""


class InputError(ValueError):
    """Bad user input: the message names the file or value and the problem, in one line."""
