"""CEODE's exceptions and warnings (the extension raises them)."""


class CEodeError(RuntimeError):
    """A CEODE call returned a negative flag.

    flag is the C return flag (an int < 0), flag_name its name ("CE_ILL_INPUT", ...),
    and str(error) is CEODE's own message, naming the cause.
    """

    def __init__(self, flag, flag_name, message):
        super().__init__(message)
        self.flag = int(flag)
        self.flag_name = str(flag_name)

    def __reduce__(self):
        return (type(self), (self.flag, self.flag_name, str(self)))


class CEodeWarning(RuntimeWarning):
    """A warning CEODE reported (CE_WARNING), e.g. the stability guard's."""
