"""Not part of the package: the clone's root. Where the clone is a folder named connenv and Python runs in the folder
above it, ``import connenv`` finds this folder before the installed package; without this file it would be an empty
namespace package (``NamespaceNotFound: Namespace connenv not found`` at gym.make). This file makes it the package
inside it, connenv/connenv, instead: its modules and its registration, as if imported from the install. Imported
under any other name (pytest collects the clone's root as a package) it does nothing.
"""

if __name__ == "connenv":
    import os as _os

    __path__ = [_os.path.join(_os.path.dirname(_os.path.abspath(__file__)), "connenv")]
    __file__ = _os.path.join(__path__[0], "__init__.py")
    with open(__file__, encoding="utf-8") as _source:
        exec(compile(_source.read(), __file__, "exec"))  # noqa: S102 (the package's __init__, as its import runs it)
    del _os, _source
