"""What the Python rostests share: where the shared data is, the package's built tools, a
node's pid through the master. Imported from the tests' own folder (their sys.path[0])."""
import os
import xmlrpc.client

import rosgraph
import rosnode
import roslib.packages

PKG = 'urban_detection'


def shared_data():
    """../shared/data beside the source tree, or UD_SHARED_DATA."""
    if os.environ.get('UD_SHARED_DATA'):
        return os.environ['UD_SHARED_DATA']
    src = os.path.realpath(roslib.packages.get_pkg_dir(PKG))
    return os.path.normpath(os.path.join(src, '..', 'shared', 'data'))


def tool(name):
    """The path of the built executable `name` of this package."""
    paths = roslib.packages.find_node(PKG, name)
    if not paths:
        raise RuntimeError('%s is not built' % name)
    return paths[0]


def node_pid(name, caller):
    """The pid of a node registered with the master, None if it does not answer."""
    try:
        uri = rosnode.get_api_uri(rosgraph.Master(caller), name, skip_cache=True)
        if not uri:
            return None
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid(caller)
        return pid if code == 1 else None
    except (OSError, xmlrpc.client.Error):
        return None
