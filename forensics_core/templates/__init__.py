"""The report's Jinja2 templates and stylesheet (installed as ``forensics_core.templates``).

Read them with :func:`forensics_core.report.render.template_text`; they are
package data, so an editable and a regular install find them alike.
"""
