"""The HP-GL plotter simulator (HP 7475A, 7550A, 7440A); ``plotter.HPGLPlotter`` and ``plotter.create`` tie it together.

``models`` the models and papers · ``parsing`` HP-GL and ``ESC .`` syntax · ``params`` errors, parameter
checks and the table shape · ``machine`` pen, coordinate systems, graphics state, motion planning ·
``motion`` move timing · ``instructions`` / ``labels`` / ``output`` one method per instruction and their
tables (``output`` also the RS-232 interface and device control) · ``drawing`` the ink on the sheet.
"""
