"""gliderplan.language"""
