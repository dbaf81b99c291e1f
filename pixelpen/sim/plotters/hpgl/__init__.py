"""The HP-GL plotter simulator (HP 7475A, 7550A, 7440A): parsing, instructions, labels and the sheet."""
