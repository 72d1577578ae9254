"""gliderplan.runtime"""
