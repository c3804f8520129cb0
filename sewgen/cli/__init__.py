"""The ``sewgen`` command, one module per command: ``main`` (the parser and the entry point), ``mechanism``
(list, params, kinematics, forces), ``analyze``, ``timing``, ``balance`` and ``balance_machine`` (``sewgen
balance``), ``study`` (``sewgen study``); ``common`` holds what several share (the console, the usage error,
quantities and arguments). The top layer.
"""
