"""The one error type the tracer raises for problems a user can act on."""


class SpectralError(ValueError):
    """A message naming the problem in user terms: which file, grid, spectrum or setting, and why.

    Raised for bad input (missing or corrupt files, invalid values, unsupported settings) so that the
    CLI and the add-on can show it as is, without a traceback from deep inside NumPy.
    """
