"""The ``sewgen`` command: ``main`` (the parser and the mechanism, machine and timing commands),
``balance`` and ``balance_machine`` (``sewgen balance``), ``study`` (``sewgen study``). The top layer.
"""
