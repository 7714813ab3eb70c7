"""The main window's panels: widgets over their models, each testable on its own."""
