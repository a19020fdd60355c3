"""The camera half of ForaNav. Each sub-folder is one JeVois module, deployed as-is to
``JEVOIS:/modules/<Vendor>/<Module>/`` (the ``__init__.py`` files exist only for host imports and are not deployed).
"""
