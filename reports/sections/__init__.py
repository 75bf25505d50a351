"""The sections of the campaign report, one module each; :func:`reports.content.build` puts them in order."""
