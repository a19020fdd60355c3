"""Deployment of the camera module to a JeVois-A33: microSD card installs (`foranav deploy`) and `.jvpkg`
packages (`foranav package`).

Layout: pure cores that take file contents and return new contents or plans (``modes``, ``videomappings``,
``initscript``, ``module_files``, ``card``, ``package``), and thin adapters that read and write the card
(``card.read_card``/``card.apply_plan``, ``module_files.read_module_folder``) used by the two commands.
"""
