"""Exceptions raised for bad input: one line saying what is wrong and what to do."""


class NNMInputError(ValueError):
    """Invalid user input (matrices, springs, files, parameters).

    The message is one line: what is wrong, and what would fix it.
    """


class NNMFileError(NNMInputError):
    """A model/branch file that is missing, not HDF5, or not in the nnm format."""
