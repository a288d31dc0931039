"""The application layer: options and config, the typed stage records, the stages and the pipeline
that chains them, batch runs, progress, run folders, crash logs and the command line (``cli``).

It sits on top of the fabrication stages (``fabricate.offset``, ``cad``, ``export``, ``structure``,
``report``), which never import it, and of ``optimize``.
"""
