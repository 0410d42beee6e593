"""`astiop serve`: the console in a browser. Each tab is a console process of its own (Textual's
web driver, through textual-serve's process protocol) on the same settings, database and robot;
what the tabs share (the E-STOP latch, approvals) lives in the database, as between terminals."""
