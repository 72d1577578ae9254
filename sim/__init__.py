"""gliderplan.sim"""
