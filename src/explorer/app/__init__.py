"""Interface layer: the command line (:mod:`explorer.app.cli`, one module per command in
:mod:`explorer.app.commands`), the sweep runner
(:mod:`explorer.app.runner`), figures (:mod:`explorer.app.figures` and the paper's figures),
the interactive explorer. The only layer that imports matplotlib."""
